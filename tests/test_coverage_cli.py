"""``scenario_coverage`` through the real commands: variation + batch, a foreign child's coverage.json,
input coverage from our own runs, the plan, --fail-under, --store, a single run, and user errors.

Expected counts are worked out by hand from the variants (see ``tests/coverage_child.py``): variant
``i`` has speed ``[10, 20, 30][i // 4]``, gap ``[5, 10][i // 2 % 2]``, lane ``[left, right][i % 2]``;
gap 5 fails (0 1 4 5 8 9), speed 30 with gap 10 crashes (10 11: error), the rest pass (2 3 6 7).
"""

from __future__ import annotations

import json
import shutil
import statistics

import pytest
from coverage_support import BIN, coverage, run

pytest_plugins = ["coverage_fixtures"]

FAILED = {"cut_in0", "cut_in1", "cut_in4", "cut_in5", "cut_in8", "cut_in9"}
ERRORED = {"cut_in10", "cut_in11"}


def report(batch_root, *args) -> dict:
    done = coverage("json", *args, cwd=batch_root)
    assert done.returncode == 0, done.stdout + done.stderr
    return json.loads(done.stdout)


def items(doc: dict) -> dict[str, dict]:
    return {item["name"]: item for item in doc["items"]}


def buckets(item: dict) -> dict[str, tuple]:
    """label -> (hits, passed, failed, errored)."""
    return {b["label"]: (b["hits"], b["passed"], b["failed"], b["errored"]) for b in item["buckets"]}


def test_a_foreign_childs_coverage_is_merged_with_exact_buckets_grades_and_holes(child_batch):
    doc = report(child_batch.root, "results")
    assert doc["format"] == "scenario-coverage/report" and doc["complete"] is True
    assert doc["runs"] == {"total": 12, "passed": 4, "failed": 6, "error": 2, "skipped": 0, "pending": 0}
    by_name = items(doc)

    # ego_speed is sampled at `end`, so only the 4 passed runs have it: 36 kph (2, 3) and 72 kph (6, 7).
    ego = by_name["cut_in.ego_speed"]
    assert ego["kind"] == "cover" and ego["unit"] == "kph" and ego["range"] == [0, 150] and ego["every"] == 25
    assert buckets(ego) == {"[0..25)": (0, 0, 0, 0), "[25..50)": (2, 2, 0, 0), "[50..75)": (2, 2, 0, 0),
                            "[75..100)": (0, 0, 0, 0), "[100..125)": (0, 0, 0, 0), "[125..150]": (0, 0, 0, 0)}
    assert ego["grade"] == pytest.approx(100 * 2 / 6, abs=0.01)
    assert ego["holes"] == ["[0..25)", "[75..100)", "[100..125)", "[125..150]"]

    # An enum's members are all the goal: nobody cut in from the centre.
    side = by_name["cut_in.cut_side"]
    assert buckets(side) == {"left": (2, 2, 0, 0), "right": (2, 2, 0, 0), "center": (0, 0, 0, 0)}
    assert side["holes"] == ["center"] and side["grade"] == pytest.approx(66.67, abs=0.01)

    # The cross is a 6 x 3 grid with 4 cells hit.
    cross = by_name["cut_in.speed_x_side"]
    assert cross["kind"] == "cross" and cross["cross"]["axes"] == ["cut_in.ego_speed", "cut_in.cut_side"]
    assert [len(axis) for axis in cross["cross"]["labels"]] == [6, 3]
    assert sum(1 for b in cross["buckets"] if b["hits"]) == 4 and len(cross["holes"]) == 14
    assert cross["grade"] == pytest.approx(100 * 4 / 18, abs=0.01)

    # lateral_offset is sampled at `finish`, so the failing runs keep it: 0 for 0 1 4 5 (all failed),
    # 3 (outside [-2..2], ignored) for 8 9, -1 for 2 6, 1 for 3 7.
    offset = by_name["cut_in.lateral_offset"]
    assert buckets(offset) == {"-2": (0, 0, 0, 0), "-1": (2, 2, 0, 0), "0": (4, 0, 4, 0), "1": (2, 2, 0, 0),
                               "2": (0, 0, 0, 0)}
    assert offset["ignored"] == 2 and offset["holes"] == ["-2", "2"]
    zero = next(b for b in offset["buckets"] if b["label"] == "0")
    assert zero["pass_rate"] == 0.0 and zero["failing_runs"] == ["cut_in0", "cut_in1", "cut_in4", "cut_in5"]

    # The record keeps raw values of the 10 runs that wrote the file, with the run of each extreme.
    ttc = {i: gap * 10 / speed + (0.1 if i % 2 else 0.0)
           for i in range(10) for speed, gap in [([10, 20, 30][i // 4], [5, 10][i // 2 % 2])]}
    record = by_name["cut_in.min_ttc"]["record"]
    assert record["count"] == 10
    assert record["min"] == {"value": pytest.approx(min(ttc.values())), "run": "cut_in8"}
    assert record["max"] == {"value": pytest.approx(10.1), "run": "cut_in3"}
    assert record["median"] == pytest.approx(statistics.median(ttc.values()))
    assert by_name["cut_in.min_ttc"]["grade"] is None

    # Input coverage: a value is hit by runs with a verdict; errored runs count against its pass rate.
    assert buckets(by_name["input:cut_in.speed"]) == {"10": (4, 2, 2, 0), "20": (4, 2, 2, 0), "30": (2, 0, 2, 2)}
    speed_gap = by_name["input:cut_in.speed x cut_in.gap"]
    assert speed_gap["holes"] == ["30 × 10"] and speed_gap["grade"] == pytest.approx(100 * 5 / 6, abs=0.01)
    assert buckets(speed_gap)["30 × 10"] == (0, 0, 0, 2)

    # Overall: the mean of the 10 graded items (3 inputs at 100, crosses 83.3 / 100 / 100, then the cover items).
    grades = [100, 100, 100, 100 * 5 / 6, 100, 100, 100 * 2 / 6, 100 * 2 / 3, 300 / 5, 100 * 4 / 18]
    assert doc["grade"] == pytest.approx(sum(grades) / len(grades), abs=0.01)
    assert {r["name"] for r in doc["failing_runs"]} == FAILED | ERRORED
    crashed = next(r for r in doc["failing_runs"] if r["name"] == "cut_in10")
    assert crashed["verdict"] == "error" and crashed["log"].endswith("cut_in10/log.txt")


def test_report_fail_under_gates_ci_on_the_overall_grade(child_batch):
    below = coverage("report", "results", "--fail-under", "80", cwd=child_batch.root)
    assert below.returncode == 1
    assert below.stderr.strip() == "scenario_coverage: coverage grade 76.6 % is below --fail-under 80 %"
    above = coverage("report", "results", "--fail-under", "76.5", cwd=child_batch.root)
    assert above.returncode == 0, above.stderr
    text = above.stdout
    assert "Overall grade 76.6 %" in text and "12 run(s) (4 passed, 6 failed, 2 error)" in text
    assert "holes (4): [0..25), [75..100), [100..125), [125..150]" in text
    assert "\x1b[" not in text                   # not a terminal: plain text


def test_a_plan_weights_items_and_sets_hit_targets(child_batch):
    (child_batch.root / "plan.yaml").write_text(
        "items:\n"
        "  'input:*':\n"
        "    weight: 0\n"
        "  cut_in.cut_side:\n"
        "    at_least: 3\n"
        "  nothing.matches: {weight: 2}\n", encoding="utf-8")
    doc = report(child_batch.root, "results", "--plan", "plan.yaml")
    by_name = items(doc)
    assert by_name["cut_in.cut_side"]["grade"] == 0.0 and by_name["cut_in.cut_side"]["at_least"] == 3
    assert by_name["input:cut_in.speed"]["weight"] == 0
    # Only the cover items count now: ego 2/6, side 0/3, offset 3/5, cross 4/18.
    assert doc["grade"] == pytest.approx((100 * 2 / 6 + 0 + 60 + 100 * 4 / 18) / 4, abs=0.01)
    assert "the plan names 'nothing.matches', which matches no item" in doc["warnings"]


def test_a_bad_plan_is_one_located_error(child_batch):
    (child_batch.root / "bad_plan.yaml").write_text("items:\n  cut_in.cut_side:\n    at_least: -1\n",
                                                     encoding="utf-8")
    done = coverage("report", "results", "--plan", "bad_plan.yaml", cwd=child_batch.root)
    assert done.returncode == 1
    assert done.stderr.splitlines()[0] == (
        "bad_plan.yaml:3:15: error: at_least must be a whole number of hits, 1 or more (got '-1')")
    assert "Traceback" not in done.stderr


def test_the_store_gives_the_same_report_as_the_folder(child_batch, tmp_path):
    """The batch runner records each job's ``coverage.json`` in the store: --store reports the same as the
    folders, also once the folders are gone (another host, a cleaned workspace)."""
    url = f"sqlite:///{tmp_path / 'copy.db'}"
    shutil.copy(child_batch.root / "store.db", tmp_path / "copy.db")
    before = report(child_batch.root, "results", "--store", url)
    shutil.move(str(child_batch.results), str(child_batch.root / "moved"))     # the folders are gone now
    try:
        after = report(child_batch.root, "results", "--store", url)
        folder = report(child_batch.root, "moved")
    finally:
        shutil.move(str(child_batch.root / "moved"), str(child_batch.results))
    strip = lambda doc: ({k: v for k, v in doc.items() if k not in ("source", "notes", "failing_runs")})  # noqa: E731
    assert strip(after) == strip(folder) == strip(before)
    assert "read from their folders" not in " ".join(before["notes"])
    assert any(item["samples"] for item in after["items"] if not item["name"].startswith("input:"))


def test_input_coverage_of_our_own_runs_without_any_cover_item(execution_batch):
    doc = report(execution_batch.root, "results")
    assert doc["runs"]["total"] == 6 and doc["runs"]["passed"] == 3 and doc["runs"]["failed"] == 3
    by_name = items(doc)
    assert list(by_name) == ["input:follow.speed", "input:follow.gap", "input:follow.speed x follow.gap"]
    assert buckets(by_name["input:follow.gap"]) == {"5": (3, 0, 3, 0), "10": (3, 3, 0, 0)}
    assert by_name["input:follow.gap"]["buckets"][0]["failing_runs"] == ["follow0", "follow2", "follow4"]
    assert buckets(by_name["input:follow.speed"]) == {"10": (2, 1, 1, 0), "20": (2, 1, 1, 0), "30": (2, 1, 1, 0)}
    assert by_name["input:follow.speed x follow.gap"]["grade"] == 100.0 and doc["grade"] == 100.0


def test_a_single_run_folder(tmp_path):
    (tmp_path / "one.osc").write_text('import osc.helpers\nscenario one:\n    do serial:\n        log("hi")\n',
                                      encoding="utf-8")
    ran = run(str(BIN / "scenario_execution"), "one.osc", "-o", "r1", cwd=tmp_path)
    assert ran.returncode == 0, ran.stdout + ran.stderr
    done = coverage("report", "r1", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "r1: 1 run(s) (1 passed)" in done.stdout
    # A run folder holding a coverage.json (phase 2 writes it beside test.xml): its items are reported.
    from coverage_engine.coverage.run_file import RunCoverageBuilder, write_run_coverage

    builder = RunCoverageBuilder("one", variant="one")
    builder.cover("mode", path="one", value_type="bool").add(True)
    write_run_coverage(tmp_path / "r1", builder.build("passed"))
    doc = json.loads(coverage("json", "r1", cwd=tmp_path).stdout)
    assert buckets(items(doc)["one.mode"]) == {"false": (0, 0, 0, 0), "true": (1, 1, 0, 0)}
    assert doc["grade"] == 50.0


def test_a_batch_still_running_is_reported_as_incomplete(child_batch, tmp_path):
    partial = tmp_path / "partial"
    shutil.copytree(child_batch.results, partial)
    (partial / "test.xml").unlink()                          # the merged report comes at the end
    (partial / "cut_in7" / "test.xml").unlink()              # still running: only its log so far
    (partial / "cut_in7" / "coverage.json").unlink()
    doc = report(tmp_path, "partial")
    # Without the merged report the two crashed jobs (a log, no test.xml) cannot be told from running ones.
    assert doc["complete"] is False and doc["runs"]["total"] == 12
    assert doc["runs"]["pending"] == 3 and doc["runs"]["error"] == 0
    assert "still running" in doc["notes"][0]
    text = coverage("report", "partial", cwd=tmp_path).stdout
    assert "INCOMPLETE: the batch is still running or was stopped" in text
    # The store view of a batch whose jobs are queued says so too.
    url = f"sqlite:///{tmp_path / 'queued.db'}"
    run(str(BIN / "scenario_batch_execution"), "-i", str(child_batch.root / "out"), "-o", "later", "--store", url,
        "--enqueue-only", "--", "true", "{SCENARIO}", "{OUTPUT_DIR}", cwd=tmp_path)
    queued = report(tmp_path, "--store", url)
    assert queued["complete"] is False and queued["runs"]["pending"] == 12
    assert queued["notes"] == ["the batch is still running: 12 job(s) have not finished; this report covers "
                               "the finished ones"]


def test_a_broken_coverage_json_is_a_located_warning_and_the_run_still_counts(child_batch, tmp_path):
    results = tmp_path / "results"
    shutil.copytree(child_batch.results, results)
    (results / "cut_in2" / "coverage.json").write_text(
        '{"format": "scenario-coverage/run", "format_version": 1,\n'
        ' "run": {"scenario": "cut_in", "verdict": "passed"},\n'
        ' "items": [{"name": "x", "kind": "cover", "type": "int", "every": 2}]}\n', encoding="utf-8")
    doc = report(tmp_path, "results")
    assert doc["runs"]["passed"] == 4
    assert any(w.startswith(f"{results / 'cut_in2' / 'coverage.json'}:3:67: error: items[0].every: 'every' needs "
                            f"a 'range'") for w in doc["warnings"]), doc["warnings"]


@pytest.mark.parametrize(("args", "message"), [
    (["report"], "missing RESULTS"),
    (["report", "results", "--batch", "1"], "--batch needs --store"),
    (["report", "results", "--fail-under", "150"], "150.0 is not in the range 0<=x<=100"),
    (["report", "results", "--colour"], "No such option '--colour'"),
    (["publish", "results"], "No such command 'publish'"),
])
def test_usage_errors_exit_2_with_the_usage_and_one_error_line(child_batch, args, message):
    done = coverage(*args, cwd=child_batch.root)
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.startswith("Usage: scenario_coverage")
    assert done.stderr.strip().splitlines()[-1].startswith("Error: ") and message in done.stderr.splitlines()[-1]
    assert "Traceback" not in done.stderr


def test_results_that_are_not_there_are_one_clear_line(tmp_path):
    done = coverage("html", "nowhere", cwd=tmp_path)
    assert done.returncode == 1 and done.stderr == "nowhere: error: no such folder\n"
    (tmp_path / "empty").mkdir()
    done = coverage("report", "empty", cwd=tmp_path)
    assert done.returncode == 1
    assert done.stderr.startswith("empty: error: no results here")


def _sqlite(path, *statements: str) -> bytes:
    """Run ``statements`` on the SQLite file at ``path``; its bytes afterwards."""
    import sqlite3
    from contextlib import closing

    with closing(sqlite3.connect(path)) as conn, conn:
        for statement in statements:
            conn.execute(statement)
    return path.read_bytes()


def test_a_store_that_is_not_there_is_a_usage_error_and_nothing_is_created(tmp_path):
    done = coverage("report", "--store", f"sqlite:///{tmp_path / 'none.db'}", cwd=tmp_path)
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr == f"error: there is no store at {tmp_path / 'none.db'} (nothing was created)\n"
    # Without RESULTS the default store is read; when there is none, RESULTS is what is missing.
    done = coverage("json", cwd=tmp_path)
    assert done.returncode == 2 and "missing RESULTS" in done.stderr and ".scenario_store.db" in done.stderr
    assert list(tmp_path.iterdir()) == []
    # A SQLite file that holds no store is not made one.
    other = tmp_path / "other.db"
    before = _sqlite(other, "CREATE TABLE t (x INTEGER)")
    done = coverage("html", "--store", f"sqlite:///{other}", cwd=tmp_path)
    assert done.returncode == 2 and done.stderr == f"error: {other} is not a scenario store (it has no " \
                                                   f"store_meta table)\n"
    assert other.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["other.db"]
    # A store without batches (variation records only, say) is one line and exit 1.
    from store.database import ensure_schema, open_engine

    engine = open_engine(f"sqlite:///{tmp_path / 'empty.db'}")
    ensure_schema(engine, [])
    engine.dispose()
    done = coverage("report", "--store", f"sqlite:///{tmp_path / 'empty.db'}", cwd=tmp_path)
    assert done.returncode == 1 and done.stderr == f"error: the store sqlite:///{tmp_path / 'empty.db'} holds no batch\n"


def test_an_older_store_is_read_as_it_is_and_a_newer_one_refused(child_batch, tmp_path):
    """Reading never upgrades: a version-1 store (no coverage tables) reports, byte for byte unchanged."""
    old = tmp_path / "old.db"
    shutil.copy(child_batch.root / "store.db", old)
    before = _sqlite(old, "UPDATE store_meta SET schema_version = 1", "DROP TABLE IF EXISTS job_coverage",
                     "DROP TABLE IF EXISTS coverage_schemas")
    doc = report(child_batch.root, "results", "--store", f"sqlite:///{old}")
    assert doc["runs"]["total"] == 12 and doc["runs"]["failed"] == 6
    assert doc["items"] == report(child_batch.root, "results")["items"]     # job folders: as from the folder
    assert old.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.db"]

    newer = _sqlite(old, "UPDATE store_meta SET schema_version = 99")
    done = coverage("report", "--store", f"sqlite:///{old}", cwd=tmp_path)
    assert done.returncode == 1, done.stdout + done.stderr
    assert done.stderr == (f"error: the store at sqlite:///{old} has schema version 99, this release reads "
                           f"versions 1, 2; use a matching release\n")
    assert old.read_bytes() == newer


def test_fail_under_compares_the_grade_as_shown(child_batch):
    """A report that says 76.6 % passes --fail-under 76.6 even when the grade is 76.56 (coverage.py's rule)."""
    shown = coverage("report", "results", cwd=child_batch.root)
    assert "Overall grade 76.6 %" in shown.stdout
    assert coverage("report", "results", "--fail-under", "76.6", cwd=child_batch.root).returncode == 0
    assert coverage("report", "results", "--fail-under", "76.7", cwd=child_batch.root).returncode == 1


def test_plain_report_cuts_nothing_and_pads_nothing(child_batch):
    """In a pipe or a file (a CI log) the report is as wide as its longest item needs: no name or cell
    cut with an ellipsis or wrapped, and no line padded with trailing blanks."""
    shown = coverage("report", "results", cwd=child_batch.root)
    assert shown.returncode == 0
    assert "…" not in shown.stdout
    assert all(line == line.rstrip() for line in shown.stdout.splitlines())
    rows = [line for line in shown.stdout.splitlines() if line.startswith(" input:") or line.startswith(" cut_in")]
    assert rows and all(line.split()[0] for line in rows)
