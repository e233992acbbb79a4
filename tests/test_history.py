"""Repeats, flaky variants, diff, history and triage through the real CLIs (issue 36).

Every test runs the console scripts as subprocesses on real SQLite stores, output read from a pipe.
The flaky scenario draws from a random generator seeded with its attempt number (``$SCENARIO_ATTEMPT``),
so which attempts fail is known in advance and the test is not itself flaky.
"""

from __future__ import annotations

import json
import math
import os
import random
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from coverage_support import chromium_page
from tests_schema import assert_valid

BIN = Path(sys.executable).parent

pytest_plugins = ["batch_stores"]            # store_url: a fresh SQLite file, a fresh PostgreSQL database

DRAW = '''import os, random
def draw() -> float:
    return random.Random("seed-" + os.environ.get("SCENARIO_ATTEMPT", "0")).random()
'''

FLAKY = '''import osc.helpers

struct lib:
    def draw() -> float is external draw.draw()

scenario flaky:
    do serial:
        compare(lib.draw(), ">=", 0.3)
'''


def _env() -> dict[str, str]:
    env = dict(os.environ, NO_COLOR="1")
    env.pop("SCENARIO_STORE", None)
    return env


def run(tool: str, *args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(BIN / tool), *args], cwd=cwd, env=_env(), capture_output=True, text=True, timeout=300)


def _expected_passes(count: int) -> list[bool]:
    return [random.Random(f"seed-{k}").random() >= 0.3 for k in range(1, count + 1)]


def _suites(report: Path) -> dict[str, dict[str, str]]:
    root = ET.parse(report).getroot()
    return {s.get("name"): {p.get("name"): p.get("value") for p in s.iter("property")} for s in root.iter("testsuite")}


def _flaky_input(tmp_path: Path) -> Path:
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "draw.py").write_text(DRAW)
    (folder / "flaky.osc").write_text(FLAKY)
    return folder


def test_repeat_10_gives_a_pass_rate_within_the_binomial_bound_and_calls_the_variant_flaky(tmp_path):
    _flaky_input(tmp_path)
    store = f"sqlite:///{tmp_path / 'store.db'}"
    done = run("scenario_batch_execution", "-i", "in", "-o", "results", "--repeat", "10", "-j", "2", "--store", store,
               cwd=tmp_path)
    expected = _expected_passes(10)
    passed = sum(expected)
    assert 0 < passed < 10                                   # the seeds give a flaky variant
    # 10 draws with P(fail) = 0.3: the pass rate lies within 3 standard deviations of 0.7
    assert abs(passed / 10 - 0.7) <= 3 * math.sqrt(0.7 * 0.3 / 10)
    assert done.returncode == 1, done.stderr                 # --pass-rate 1.0 by default: the variant fails
    lines = done.stdout.splitlines()
    assert lines[-1].startswith(f"batch 1: 1 variant(s) x 10 attempts: 1 failed; {passed} of 10 attempt(s) passed "
                                f"({10 * passed} %); 1 flaky; report ")
    assert f"FLAKY    flaky - passed {passed} of 10 attempt(s) ({10 * passed} %, --pass-rate 100 %)" in lines
    assert f"--- {10 - passed} failure(s) of 1 kind(s) ---" in lines

    report = tmp_path / "results" / "test.xml"
    assert_valid(report)
    root = ET.parse(report).getroot()
    assert root.get("tests") == "1" and root.get("failures") == "1"          # one testcase per variant
    props = _suites(report)["flaky"]
    assert props["flaky"] == "true" and props["repeat.passed"] == str(passed) and props["repeat.ran"] == "10"
    assert [props[f"repeat.attempt.{k}"] for k in range(1, 11)] == ["passed" if p else "failed" for p in expected]
    assert all((tmp_path / "results" / f"flaky@{k}" / "test.xml").is_file() for k in range(1, 11))
    assert "attempt 10: " in root.find(".//system-out").text

    # coverage counts every attempt; status lists the flaky variant
    cover = run("scenario_coverage", "report", "results", cwd=tmp_path)
    assert cover.stdout.splitlines()[0].startswith(f"Scenario coverage of results: 10 run(s) ({passed} passed, "
                                                   f"{10 - passed} failed)  [complete]")
    assert cover.stdout.splitlines()[-3:] == ["Flaky variants (1)", f"  flaky - passed {passed} of 10 attempt(s)", ""]
    as_json = json.loads(run("scenario_coverage", "json", "--store", store, cwd=tmp_path).stdout)
    assert as_json["flaky"] == [{"name": "flaky", "detail": f"passed {passed} of 10 run(s) in this store"}]
    status = run("scenario_batch_execution", "status", "--store", store, "--list", "flaky", "--json", cwd=tmp_path)
    assert json.loads(status.stdout)["flaky"] == [{"name": "flaky", "passed": passed, "not_passed": 10 - passed}]

    # with a pass rate the variant meets, it passes, and is still flaky
    again = run("scenario_batch_execution", "-i", "in", "-o", "results2", "--repeat", "10", "--pass-rate", "0.5",
                "--store", store, cwd=tmp_path)
    assert again.returncode == 0, again.stdout
    assert _suites(tmp_path / "results2" / "test.xml")["flaky"]["flaky"] == "true"


def test_until_fail_stops_a_variant_at_its_first_failure(tmp_path):
    _flaky_input(tmp_path)
    done = run("scenario_batch_execution", "-i", "in", "-o", "results", "--repeat", "until-fail:20",
               "--store", f"sqlite:///{tmp_path / 's.db'}", cwd=tmp_path)
    first = _expected_passes(20).index(False) + 1
    assert done.returncode == 1
    props = _suites(tmp_path / "results" / "test.xml")["flaky"]
    outcomes = [props[f"repeat.attempt.{k}"] for k in range(1, 21)]
    assert outcomes == ["passed"] * (first - 1) + ["failed"] + ["not run"] * (20 - first)
    assert props["repeat.ran"] == str(first)
    assert not (tmp_path / "results" / f"flaky@{first + 1}").exists()
    assert_valid(tmp_path / "results" / "test.xml")
    bad = run("scenario_batch_execution", "-i", "in", "-o", "r", "--repeat", "until-fail:x", cwd=tmp_path)
    assert bad.returncode == 2 and "neither a number nor 'until-fail:N'" in bad.stderr


GAP = """import osc.helpers
scenario gap_check:
    gap: float = 1.0 with:
        keep(it in [1.5, 2.0, 3.0])
    do serial:
        compare(gap, ">", 1.0)
"""


def test_diff_names_exactly_the_regression_and_exits_1(tmp_path):
    (tmp_path / "gap.osc").write_text(GAP)
    store = f"sqlite:///{tmp_path / 's.db'}"
    assert run("scenario_variation", "gap.osc", "--store", store, cwd=tmp_path).returncode == 0
    first = run("scenario_batch_execution", "-i", "out", "-o", "monday", "--store", store, cwd=tmp_path)
    assert first.returncode == 0, first.stdout
    changed = sorted((tmp_path / "out").glob("*.sce"))[1]
    changed.write_text(changed.read_text().replace('">", 1.0', '">", 5.0'))
    second = run("scenario_batch_execution", "-i", "out", "-o", "tuesday", "--store", store, cwd=tmp_path)
    assert second.returncode == 1
    name = _suites(tmp_path / "tuesday" / "test.xml")
    failing = [n for n, p in name.items() if p["status"] == "failed"]
    assert len(failing) == 1

    diff = run("scenario_coverage", "diff", "monday", "tuesday", cwd=tmp_path)
    assert diff.returncode == 1, diff.stderr
    lines = diff.stdout.splitlines()
    assert lines[2].startswith("1 regression(s), 0 fixed, 0 new (0 failing), 0 gone, 0 flaky, 0 still failing")
    assert lines[3] == "regressions: passed in A, fail in B (1):"
    assert lines[4].startswith(f"  {failing[0]} (failed) - 'compare' at ") and "failed: 2.0 > 5.0 is False" in lines[4]

    as_json = json.loads(run("scenario_coverage", "diff", "monday", "tuesday", "--json", cwd=tmp_path).stdout)
    assert [r["name"] for r in as_json["regressions"]] == failing and as_json["new_failures"] == 1
    assert as_json["fixed"] == as_json["new"] == as_json["gone"] == []
    by_id = json.loads(run("scenario_coverage", "diff", "1", "2", "--store", store, "--json", cwd=tmp_path).stdout)
    assert [r["name"] for r in by_id["regressions"]] == failing
    back = run("scenario_coverage", "diff", "tuesday", "monday", cwd=tmp_path)
    assert back.returncode == 0 and "0 regression(s), 1 fixed" in back.stdout
    # a variant dropped: gone, and the bucket of its value lost
    dropped = sorted((tmp_path / "out").glob("*.sce"))[2]
    dropped.unlink()
    assert run("scenario_batch_execution", "-i", "out", "-o", "wednesday", "--store", store, cwd=tmp_path).returncode == 1
    gone = json.loads(run("scenario_coverage", "diff", "tuesday", "wednesday", "--json", cwd=tmp_path).stdout)
    assert [r["name"] for r in gone["gone"]] == [dropped.stem] and gone["regressions"] == gone["new"] == []
    assert gone["items"] == [{"item": "input:gap_check.gap", "gained": [], "lost": ["3"]}]
    missing = run("scenario_coverage", "diff", "monday", "nowhere", cwd=tmp_path)
    assert missing.returncode == 1 and "nowhere: error: no such results folder" in missing.stderr
    assert "Traceback" not in missing.stderr


def _verdict_files(folder: Path, failing: int, total: int = 4) -> None:
    if folder.exists():
        for old in folder.iterdir():
            old.unlink()
    folder.mkdir(exist_ok=True)
    for index in range(total):
        limit = 5 if index < failing else 0
        (folder / f"case{index}.osc").write_text(f"import osc.helpers\nscenario case{index}:\n    do serial:\n"
                                                 f"        compare({index + 1}, \">\", {limit})\n")


def test_history_shows_one_row_per_batch_with_its_pass_rate(tmp_path, store_url):
    store = store_url
    for batch, failing in enumerate((0, 1, 3), 1):
        _verdict_files(tmp_path / "in", failing)
        done = run("scenario_batch_execution", "-i", "in", "-o", f"results{batch}", "--store", store, cwd=tmp_path)
        assert done.returncode == (0 if failing == 0 else 1)
    shown = run("scenario_coverage", "history", "--store", store, cwd=tmp_path)
    assert shown.returncode == 0, shown.stderr
    lines = shown.stdout.splitlines()
    assert lines[0].split() == ["batch", "date", "runs", "pass", "rate", "variants", "flaky", "grade", "holes"]
    rows = [line.split() for line in lines[1:]]
    assert len(rows) == 3
    assert [(r[0], r[3], r[4]) for r in rows[:2]] == [("1", "4", "100.0"), ("2", "4", "75.0")]
    assert rows[2][:2] == ["*", "3"] and rows[2][4:6] == ["4", "25.0"]
    document = json.loads(run("scenario_coverage", "history", "--store", store, "--json", cwd=tmp_path).stdout)
    assert [b["pass_rate"] for b in document["batches"]] == [100.0, 75.0, 25.0] and document["current"] == 3
    # the results folder keeps the trend up to its batch
    kept = json.loads((tmp_path / "results2" / "history.json").read_text())
    assert [b["batch"] for b in kept["batches"]] == [1, 2] and kept["current"] == 2
    # diff by batch ids: case1 and case2 pass in batch 2 and fail in batch 3, case0 fails in both
    compared = run("scenario_coverage", "diff", "2", "3", "--store", store, "--json", cwd=tmp_path)
    assert compared.returncode == 1
    document = json.loads(compared.stdout)
    assert [r["name"] for r in document["regressions"]] == ["case1", "case2"] and document["still_failing"] == 1
    empty = run("scenario_coverage", "history", "--store", f"sqlite:///{tmp_path / 'none.db'}", cwd=tmp_path)
    assert empty.returncode == 2 and "Traceback" not in empty.stderr


TRIAGE = """import osc.helpers
scenario tri:
    kind: int = 1 with:
        keep(it in [1, 2, 3])
    n: int = 1 with:
        keep(it in [1, 2, 3, 4, 5, 6, 7])
    do serial:
        compare(kind, "!=", 1)
        compare(kind, "!=", 2)
        compare(kind, "!=", 3)
"""


def test_triage_groups_20_failures_of_3_kinds_into_3_groups(tmp_path):
    (tmp_path / "tri.osc").write_text(TRIAGE)
    store = f"sqlite:///{tmp_path / 's.db'}"
    assert run("scenario_variation", "tri.osc", "--store", store, cwd=tmp_path).returncode == 0
    (tmp_path / "out" / "tri20.sce").unlink()                # 21 variants less one: 7 + 7 + 6 failures
    done = run("scenario_batch_execution", "-i", "out", "-o", "results", "-j", "2", "--store", store, cwd=tmp_path)
    assert done.returncode == 1
    lines = done.stdout.splitlines()
    at = lines.index("--- 20 failure(s) of 3 kind(s) ---")
    groups = lines[at + 1:at + 10]
    assert [g.split(" x ")[0].strip() for g in groups[0::3]] == ["7", "7", "6"]
    assert [g.strip() for g in groups[2::3]] == ["all have: kind=1", "all have: kind=2", "all have: kind=3"]
    assert "failed: 3 != 3 is False" in groups[6] and ".sce:25:9)" in groups[6]
    assert lines[at + 10] == "--- 20 job(s) did not pass ---"

    page = tmp_path / "report.html"
    assert run("scenario_coverage", "html", "results", "-o", str(page), cwd=tmp_path).returncode == 0
    text = page.read_text()
    assert "Failures by kind (20 in 3 group(s))" in text and "kind=3" in text


def test_the_html_trend_chart_in_chromium(tmp_path):
    """Three batches of one store: the page of the third shows three bars, two lines, the third batch marked,
    with nothing loaded but the file; the chart is screenshot for CI's artefacts."""
    from test_coverage_html import artifacts

    store = f"sqlite:///{tmp_path / 's.db'}"
    for batch, failing in enumerate((0, 1, 3), 1):
        _verdict_files(tmp_path / "in", failing)
        run("scenario_batch_execution", "-i", "in", "-o", f"results{batch}", "--store", store, cwd=tmp_path)
    page_file = tmp_path / "report.html"
    done = run("scenario_coverage", "html", "results3", "-o", str(page_file), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    with chromium_page(page_file, width=1100) as (page, problems, requests):
        chart = page.locator("#trend svg.trend")
        assert chart.locator("rect.runs").count() == 3 and chart.locator("rect.current").count() == 1
        assert len(chart.locator("polyline.pass-rate").get_attribute("points").split()) == 3
        assert "batch 3: 4 run(s), pass rate 25.0 %" in chart.locator("rect.runs title").nth(2).text_content()
        box = chart.bounding_box()
        assert box is not None and box["width"] > 300 and box["height"] > 150
        assert "Failures by kind (3 in 1 group(s))" in page.inner_text("#triage h2")
        shot = artifacts() / "history-trend.png"
        page.locator("#trend").screenshot(path=str(shot))
    assert problems == [] and requests == [page_file.as_uri()]
    assert shot.stat().st_size > 5_000


def test_a_failure_kind_masks_numbers_quoted_names_and_the_variant_file():
    from coverage_engine.coverage.triage import Failure, group_failures, reason_key

    assert reason_key("'compare' (/o/cut12.sce:17:9) failed: 0.5 > 1.0 is False") == \
        ("'…' () failed: # > # is False", "cut#.sce:17")
    assert reason_key("actor 'npc1' at 0x7f3a collided") == ("actor '…' at 0x… collided", None)
    groups = group_failures([Failure("a", "x.osc:3:1: speed 84.2 above 80", {"s.road": "dry", "s.v": 1.0}),
                             Failure("b", "x.osc:3:1: speed 91.7 above 80", {"s.road": "dry", "s.v": 2.0}),
                             Failure("c", "x.osc:4:1: speed 91.7 above 80", {"s.road": "dry"})])
    assert [(g.count, g.location, g.common) for g in groups] == [(2, "x.osc:3", (("s.road", "dry"),)),
                                                                  (1, "x.osc:4", ())]
