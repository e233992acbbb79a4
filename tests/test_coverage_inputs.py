"""Input coverage is measured against what the variation declared, through the real commands, in a pipe.

Issue 31: a batch of 2 of 6 variants reports the values it did not run as holes; a range drawn by a
sampler is bucketed over its declared range with round edges in its unit; drawn values are shown
rounded in names and headers but kept exact in properties and files; a bucket only failing runs
reached is *not sampled*, not a hole; several results folders and a folder of shards merge.
"""

from __future__ import annotations

import json
import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from coverage_support import BIN, coverage, run

LANES = """\
import osc.helpers

enum surface_kind: [dry, wet]

scenario road_test:
    lanes: int with:
        keep(it in [1, 2, 3])
    surface: surface_kind with:
        keep(it in [surface_kind!dry, surface_kind!wet])
    do serial:
        wait elapsed(10ms)
"""

SPEED = """\
import osc.helpers

scenario drive:
    speed: speed with:
        keep(it in [20kph..120kph])
    gap: time with:
        keep(it in [2.5s, 1.0s, 2.0s, 1.5s])
    do serial:
        wait elapsed(10ms)
"""

GAP = """\
import osc.helpers

scenario gap_test:
    gap: length with:
        keep(it in [2m, 4m, 6m, 8m])
    cover(gap, unit: m, range: [0..10], every: 2)
    do serial:
        wait elapsed(10ms)
        compare(gap, ">", 5m)
"""


def _vary(folder: Path, name: str, text: str, *options: str) -> None:
    (folder / f"{name}.osc").write_text(text, encoding="utf-8")
    run(str(BIN / "scenario_variation"), f"{name}.osc", "-o", "out", *options, cwd=folder)


def _batch(folder: Path, source: str, output: str, *options: str) -> None:
    run(str(BIN / "scenario_batch_execution"), "-i", source, "-o", output, *options, cwd=folder)


def _items(folder: Path, *args: str) -> dict[str, dict]:
    done = coverage("json", *args, cwd=folder)
    assert done.returncode == 0, done.stderr
    return {item["name"]: item for item in json.loads(done.stdout)["items"]}


def test_values_declared_but_not_run_are_holes(tmp_path):
    _vary(tmp_path, "lanes", LANES)
    (tmp_path / "two").mkdir()
    for name in ("lanes0.sce", "lanes1.sce"):          # lanes 1 on a dry and a wet road
        shutil.copy(tmp_path / "out" / name, tmp_path / "two" / name)
    _batch(tmp_path, "two", "results")
    items = _items(tmp_path, "results")
    lanes = items["input:road_test.lanes"]
    assert [b["label"] for b in lanes["buckets"]] == ["1", "2", "3"] and lanes["holes"] == ["2", "3"]
    assert items["input:road_test.surface"]["holes"] == []
    cross = items["input:road_test.lanes x road_test.surface"]
    assert len(cross["buckets"]) == 6 and sum(b["covered"] for b in cross["buckets"]) == 2
    text = coverage("report", "results", cwd=tmp_path).stdout
    assert " input:road_test.lanes                      varied parameter                1/3      2" in text
    assert "  holes (2): 2, 3" in text


def test_the_store_knows_the_declared_values_too(tmp_path):
    _vary(tmp_path, "lanes", LANES)
    _batch(tmp_path, "out", "results", "--shard", "1/3")
    store = _items(tmp_path, "results", "--store", f"sqlite:///{tmp_path}/.scenario_store.db")
    folder = _items(tmp_path, "results")
    assert store == folder
    lanes = store["input:road_test.lanes"]
    assert [b["label"] for b in lanes["buckets"]] == ["1", "2", "3"]
    assert len(store["input:road_test.lanes x road_test.surface"]["buckets"]) == 6


def test_a_drawn_range_has_round_buckets_over_its_declared_range(tmp_path):
    _vary(tmp_path, "drive", SPEED, "--strategy", "lhs", "--samples", "10", "--seed", "5")
    header = (tmp_path / "out" / "drive0.sce").read_text(encoding="utf-8")
    assert '# domain {"key": "drive.speed", "range": [20.0, 120.0], "unit": "kph", "samples": 10}' in header
    _batch(tmp_path, "out", "results")
    items = _items(tmp_path, "results")
    speed = items["input:drive.speed"]
    # 10 samples: at most 5 buckets, of a round width (20 kph), spanning the declared 20..120 kph.
    assert [b["label"] for b in speed["buckets"]] == ["[20 kph..40 kph)", "[40 kph..60 kph)", "[60 kph..80 kph)",
                                                      "[80 kph..100 kph)", "[100 kph..120 kph]"]
    assert speed["holes"] == []                         # a Latin hypercube puts two points in each
    gap = items["input:drive.gap"]
    assert [b["label"] for b in gap["buckets"]] == ["1.0s", "1.5s", "2.0s", "2.5s"]    # numeric, not as listed
    report = ET.parse(tmp_path / "results" / "test.xml").getroot()
    suite = next(s for s in report.iter("testsuite") if s.get("name") == "drive0")
    exact = {p.get("name"): p.get("value") for p in suite.iter("property")}
    case = suite.find("testcase")
    assert case is not None
    drawn = float(exact["variation.drive.speed"])
    assert case.get("name").startswith(f"drive0[speed={drawn:.4g}kph,gap=")
    assert len(exact["variation.drive.speed"]) > 8                       # the property keeps every digit
    assert f"# drive.speed = {drawn:.4g}kph\n" in header and f'"drive.speed": {drawn!r}' in header


def test_every_of_a_cover_sets_the_width_of_a_drawn_parameter(tmp_path):
    text = SPEED.replace("    do serial:", "    cover(speed, unit: kph, range: [0..150], every: 25)\n    do serial:")
    _vary(tmp_path, "drive", text, "--strategy", "random", "--samples", "8", "--seed", "2")
    _batch(tmp_path, "out", "results")
    speed = _items(tmp_path, "results")["input:drive.speed"]
    # Inner edges every 25 kph; the first and last buckets end at the declared 20 and 120 kph.
    assert [b["label"] for b in speed["buckets"]] == ["[20 kph..25 kph)", "[25 kph..50 kph)", "[50 kph..75 kph)",
                                                      "[75 kph..100 kph)", "[100 kph..120 kph]"]


def test_a_bucket_only_failing_runs_reached_is_not_sampled(tmp_path):
    _vary(tmp_path, "gap", GAP)
    _batch(tmp_path, "out", "results")
    done = coverage("report", "results", cwd=tmp_path)
    assert done.returncode == 0
    lines = done.stdout.splitlines()
    assert " [2..4)      0     0          —  not sampled: 1 failed run(s) were here  gap0" in lines
    assert " [0..2)      0     0          —  hole" in lines
    assert "  holes (1): [0..2)" in lines
    assert "  not sampled, only failing runs were here (2): [2..4), [4..6)" in lines
    coverage_file = json.loads((tmp_path / "results" / "gap1" / "coverage.json").read_text(encoding="utf-8"))
    assert coverage_file["items"][0]["samples"] == [] and coverage_file["items"][0]["unsampled"] == [4.0]
    assert coverage_file["format_version"] == 2          # an older reader refuses it by its version
    passed = json.loads((tmp_path / "results" / "gap3" / "coverage.json").read_text(encoding="utf-8"))
    assert passed["format_version"] == 1 and "unsampled" not in passed["items"][0]


@pytest.mark.parametrize("layout", ["folders", "shards"])
def test_several_results_folders_are_one_report(tmp_path, layout):
    _vary(tmp_path, "lanes", LANES)
    for shard in (1, 2):
        _batch(tmp_path, "out", f"results/shard-{shard}", "--shard", f"{shard}/2")
    args = ("results/shard-1", "results/shard-2") if layout == "folders" else ("results",)
    done = coverage("report", *args, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    first = done.stdout.splitlines()[0]
    assert first.endswith(": 6 run(s) (6 passed)  [complete]"), first
    assert "note: 2 results folders merged: shard-1, shard-2" in done.stdout
    items = _items(tmp_path, *args)
    assert all(b["covered"] for b in items["input:road_test.lanes x road_test.surface"]["buckets"])


def test_a_shard_still_running_makes_the_merged_report_incomplete(tmp_path):
    _vary(tmp_path, "lanes", LANES)
    for shard in (1, 2):
        _batch(tmp_path, "out", f"results/shard-{shard}", "--shard", f"{shard}/2")
    stray = tmp_path / "results" / "shard-2" / "late_job"
    stray.mkdir()
    (stray / "log.txt").write_text("started\n", encoding="utf-8")
    done = coverage("report", "results", cwd=tmp_path)
    assert "INCOMPLETE" in done.stdout and "[complete]" not in done.stdout
    assert "results/shard-2: 1 job folder(s) are not in the merged report yet" in done.stdout


def test_one_failing_runs_folder_in_a_pipe_has_its_record_and_failure(tmp_path):
    """The crash that went unnoticed: a single run's folder with a failing run and a record() item."""
    text = GAP.replace("    do serial:", "    record(gap_kept, expression: gap, unit: m, event: finish)\n    do serial:")
    (tmp_path / "gap.osc").write_text(text.replace("keep(it in [2m, 4m, 6m, 8m])", "keep(it == 2m)"),
                                      encoding="utf-8")
    run(str(BIN / "scenario_execution"), "gap.osc", "-o", "r1", cwd=tmp_path)
    done = coverage("report", "r1", cwd=tmp_path)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    blocks = [b.splitlines()[0] for b in done.stdout.split("\n\n") if b.strip()]
    assert blocks[-2:] == ["Record items", "Failing runs (1)"], blocks
    assert re.search(r"^ gap_test\.gap_kept +m +1 +2 +r1 +2 +2 +r1$", done.stdout, re.MULTILINE), done.stdout


def test_a_shard_that_never_finished_is_named_and_the_merge_is_incomplete(tmp_path):
    _vary(tmp_path, "lanes", LANES)
    for shard in (1, 2):
        _batch(tmp_path, "out", f"results/shard-{shard}", "--shard", f"{shard}/2")
    (tmp_path / "results" / "shard-2" / "test.xml").unlink()      # stopped before it wrote its report
    done = coverage("report", "results", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0] == "Scenario coverage of results: 6 run(s) (6 passed)"
    assert "INCOMPLETE" in done.stdout
    assert "results/shard-2: no merged test.xml yet" in done.stdout


def test_a_folder_named_twice_is_counted_once(tmp_path):
    _vary(tmp_path, "lanes", LANES)
    _batch(tmp_path, "out", "results")
    done = coverage("report", "results", "./results", cwd=tmp_path)
    assert done.stdout.splitlines()[0] == "Scenario coverage of results: 6 run(s) (6 passed)  [complete]"


def test_the_results_folder_alone_knows_the_declared_values(tmp_path):
    """A CI job that downloads only the results (no .sce files): the batch's declared.json is enough."""
    _vary(tmp_path, "lanes", LANES)
    _batch(tmp_path, "out", "results", "--shard", "1/3")
    declared = json.loads((tmp_path / "results" / "declared.json").read_text(encoding="utf-8"))
    assert [d["key"] for d in declared["domains"]] == ["road_test.lanes", "road_test.surface"]
    shutil.rmtree(tmp_path / "out")
    lanes = _items(tmp_path, "results")["input:road_test.lanes"]
    assert [b["label"] for b in lanes["buckets"]] == ["1", "2", "3"]
