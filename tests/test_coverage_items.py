"""cover() and record() in the language, sampled at run time, merged over a batch (issue 13, phase 2).

Everything goes through the real commands: scenario_execution writes each run's ``coverage.json`` and
JUnit properties, scenario_variation + scenario_batch_execution (built-in runner) run the variants, and
scenario_coverage merges them. Expected buckets, grades and holes are worked out by hand in each test.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from coverage_support import BIN, coverage, run

CUT_IN = """import osc.helpers

enum side_kind: [left, right]

scenario cut_in:
    speed: speed = 50kph with:
        keep(it == 50kph)
        cover(unit: kph, range: [0..120], every: 20)
    side: side_kind = side_kind!left
    gap: float = 2.0
    var passes: int = 0
    cover(side)
    cover(side_x_speed, items: [speed, side])
    record(headway, expression: gap * 2.0, event: finish, text: "twice the gap")
    cover(big_gap, expression: gap > 1.5, ignore: gap > 100.0)
    event passed_by
    cover(passes_seen, expression: passes, event: passed_by)
    do serial:
        increment(passes)
        emit passed_by
        increment(passes)
        emit passed_by
        compare(gap, ">", 1.0)
"""


def execute(folder: Path, source: str, *args: str):
    return run(str(BIN / "scenario_execution"), source, *args, cwd=folder)


def items_of(path: Path) -> dict[str, dict]:
    doc = json.loads(path.read_text())
    return {item["name"]: item for item in doc["items"]}


def test_one_run_samples_every_kind_of_item(tmp_path):
    (tmp_path / "cut_in.osc").write_text(CUT_IN)
    done = execute(tmp_path, "cut_in.osc", "-o", "r")
    assert done.returncode == 0, done.stderr
    doc = json.loads((tmp_path / "r" / "coverage.json").read_text())
    assert doc["run"]["verdict"] == "passed"
    items = {item["name"]: item for item in doc["items"]}
    speed = items["speed"]
    assert (speed["unit"], speed["range"], speed["every"], speed["samples"]) == ("kph", [0.0, 120.0], 20.0, [50.0])
    assert items["side"]["members"] == ["left", "right"] and items["side"]["samples"] == ["left"]
    assert items["side_x_speed"]["items"] == ["speed", "side"]
    assert items["side_x_speed"]["samples"] == [[50.0, "left"]]
    assert items["headway"]["kind"] == "record" and items["headway"]["samples"] == [4.0]
    assert items["headway"]["event"] == "finish" and items["headway"]["text"] == "twice the gap"
    assert items["big_gap"]["samples"] == [True] and items["big_gap"]["ignore"] == "gap > 100.0"
    assert items["passes_seen"]["samples"] == [1, 2]          # sampled at each emit of its event
    suite = ET.parse(tmp_path / "r" / "test.xml").getroot().find("testsuite")
    assert suite is not None
    properties = {p.get("name"): p.get("value") for p in suite.iter("property")}
    assert properties["coverage.cut_in.speed"] == "50.0"
    assert properties["coverage.cut_in.side_x_speed"] == "(50.0, left)"
    assert properties["coverage.cut_in.passes_seen"] == "1, 2"


def test_a_failing_run_keeps_its_finish_items_and_loses_its_end_items(tmp_path):
    (tmp_path / "cut_in.osc").write_text(CUT_IN.replace("gap: float = 2.0", "gap: float = 0.5"))
    done = execute(tmp_path, "cut_in.osc", "-o", "r")
    assert done.returncode == 1
    doc = json.loads((tmp_path / "r" / "coverage.json").read_text())
    assert doc["run"]["verdict"] == "failed" and "compare" in doc["run"]["reason"]
    items = {item["name"]: item for item in doc["items"]}
    assert items["headway"]["samples"] == [1.0]               # finish: kept
    assert items["speed"]["samples"] == [] and items["side"]["samples"] == []   # end: lost
    assert items["passes_seen"]["samples"] == [1, 2]          # its own event came before the failure


def test_variants_merge_into_exact_buckets_grades_and_holes(tmp_path):
    varied = CUT_IN.replace("        keep(it == 50kph)\n", "        keep(it in [30kph, 50kph, 90kph])\n").replace(
        "    gap: float = 2.0\n", "    gap: float = 2.0 with:\n        keep(it in [0.5, 2.0])\n")
    (tmp_path / "cut_in.osc").write_text(varied)
    assert run(str(BIN / "scenario_variation"), "cut_in.osc", "-o", "out", cwd=tmp_path).returncode == 0
    batch = run(str(BIN / "scenario_batch_execution"), "-i", "out", "-o", "results", "-j", "2", cwd=tmp_path)
    assert batch.returncode == 1                               # the three gap=0.5 variants fail
    done = coverage("json", "results", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    items = {item["name"]: item for item in report["items"]}
    # 6 runs: speed 30/50/90 kph x gap 0.5/2.0; only the three gap=2.0 runs pass and sample their end items.
    speed = items["cut_in.speed"]
    assert [b["hits"] for b in speed["buckets"]] == [0, 1, 1, 0, 1, 0]   # 30 -> [20..40), 50, 90 -> [80..100)
    assert speed["holes"] == ["[0..20)", "[60..80)", "[100..120]"]
    assert speed["grade"] == pytest.approx(50.0)
    assert items["cut_in.side"]["grade"] == pytest.approx(50.0) and items["cut_in.side"]["holes"] == ["right"]
    big_gap = items["cut_in.big_gap"]                           # gap 0.5 runs failed before their end:
    assert big_gap["holes"] == [] and big_gap["not_sampled"] == ["false"]       # a failing region, no hole
    assert big_gap["grade"] == pytest.approx(50.0)
    assert sorted(big_gap["buckets"][0]["failed_here"]) == sorted(r["name"] for r in report["failing_runs"])
    cross = items["cut_in.side_x_speed"]
    assert cross["grade"] == pytest.approx(25.0)               # 3 of 6 x 2 cells
    headway = items["cut_in.headway"]["record"]
    assert headway["count"] == 6 and headway["min"]["value"] == 1.0 and headway["max"]["value"] == 4.0
    gap_input = items["input:cut_in.gap"]
    assert {b["label"]: (b["hits"], b["pass_rate"]) for b in gap_input["buckets"]} == {"0.5": (3, 0.0),
                                                                                       "2": (3, 100.0)}


def test_a_variant_run_says_which_file_and_which_values_it_ran(tmp_path):
    varied = CUT_IN.replace("        keep(it == 50kph)\n", "        keep(it in [30kph, 90kph])\n")
    (tmp_path / "cut_in.osc").write_text(varied)
    assert run(str(BIN / "scenario_variation"), "cut_in.osc", "-o", "out", cwd=tmp_path).returncode == 0
    header = (tmp_path / "out" / "cut_in1.sce").read_text().split("assignment:\n", 1)[1].splitlines()[0]
    assert execute(tmp_path, "out/cut_in1.sce", "-o", "r").returncode == 0
    variant = json.loads((tmp_path / "r" / "coverage.json").read_text())["run"]
    assert (variant["source"], variant["variant"]) == ("out/cut_in1.sce", "cut_in1")
    assert variant["assignment"] == {"cut_in.speed": "90kph"} and header.strip() == '"cut_in.speed": "90kph"'
    assert execute(tmp_path, "cut_in.osc", "-o", "plain").returncode == 1      # keep(in) needs a variant
    (tmp_path / "one.osc").write_text(CUT_IN)
    assert execute(tmp_path, "one.osc", "-o", "one").returncode == 0
    plain = json.loads((tmp_path / "one" / "coverage.json").read_text())["run"]
    assert (plain["source"], plain.get("variant"), plain["assignment"]) == ("one.osc", None, {})


@pytest.mark.parametrize(("member", "message", "line", "column"), [
    ("    cover(side)\n    cover(both, items: [side, nothing])\n", "cross 'both': no cover item 'nothing'", 6, 5),
    ("    cover(g, expression: gap, every: 2)\n", "every: needs a range:", 5, 31),
    ("    cover(g, expression: gap, unit: kph)\n", "'kph' is a unit of speed, but the value is a float", 5, 31),
    ("    cover(d, expression: distance, unit: kph)\n", "'kph' is a unit of speed, not of length", 5, 36),
    ("    cover(p, expression: point)\n", "the value must be a scalar", 5, 26),
    ("    cover(side, colour: 3)\n", "cover() has no argument 'colour'", 5, 17),
    ("    record()\n", "record() needs a name", 5, 5),
    ("    cover(side)\n    cover(side)\n", "coverage item 'side' is declared twice", 6, 5),
    ("    cover(g, expression: gap, event: never)\n", "unknown event 'never'", 5, 31),
])
def test_resolution_errors_are_located(tmp_path, member, message, line, column):
    text = ("import osc.types\nenum side_kind: [left, right]\nscenario s:\n"
            "    side: side_kind = side_kind!left\n" + member +
            "    gap: float = 1.0\n    distance: length = 3m\n    point: position_3d\n    do wait elapsed(1s)\n")
    (tmp_path / "s.osc").write_text(text)
    done = execute(tmp_path, "s.osc", "-n")
    assert done.returncode == 1
    assert done.stderr.startswith(f"s.osc:{line}:{column}: error: "), done.stderr
    assert message in done.stderr and "Traceback" not in done.stderr


def test_cover_in_an_actor_is_refused_with_its_place(tmp_path):
    (tmp_path / "s.osc").write_text("actor car:\n    v: float = 1.0\n    cover(v)\n"
                                    "scenario s:\n    do wait elapsed(1s)\n")
    done = execute(tmp_path, "s.osc", "-n")
    assert done.returncode == 1
    assert done.stderr.startswith("s.osc:3:5: error: not supported: cover() in actor 'car'")
