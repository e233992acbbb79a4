"""``--bt-log`` and ``--tick-log`` (issue 33, item 4): the reference 1.8.0's recording options, through the real CLI.

The files are read as a tool would read them: JSON lines and CSV, from a run that fails, a step-based run,
a run of two scenarios and a run killed in the middle.
"""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import time
from pathlib import Path

from cli_support import EXAMPLES, EXE, run_cli

FAILING = """import osc.helpers

scenario checked:
    gap: float = 0.5
    do serial:
        log("start")
        parallel:
            wait elapsed(0.3s)
            log("side")
        compare(gap, ">", 1.0)
        log("never")
"""


def records(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]


def rows(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as handle:
        return list(csv.DictReader(handle))


def test_bt_log_holds_the_tree_then_each_status_change(tmp_path):
    (tmp_path / "checked.osc").write_text(FAILING, encoding="utf-8")
    done = run_cli("checked.osc", "-o", "out", "--bt-log", cwd=tmp_path)
    assert done.returncode == 1, done.stdout
    assert f"Recording behaviour tree status to {tmp_path / 'out' / 'behaviors.jsonl'}" in done.stdout
    meta, *lines = records(tmp_path / "out/behaviors.jsonl")
    assert meta["format"] == "behavior_tree_log" and meta["version"] == 1 and meta["scenario"] == "checked"
    assert meta["clock"] == "monotonic" and meta["tick_period"] == 0.1 and len(meta["scenario_sha256"]) == 64
    initial = [line for line in lines if line["timestamp"] == 0.0]
    assert {line["status"] for line in initial} == {"INVALID"}
    names = [line["behavior_name"] for line in initial]
    assert names.count("log") == 3 and "compare" in names and names[-1] == "checked"   # 'never' included
    root = initial[-1]
    assert root["parent_id"] is None and root["child_index"] is None and root["type"] == "SEQUENCE"
    by_id = {line["behavior_id"]: line for line in initial}
    compare = next(line for line in initial if line["behavior_name"] == "compare")
    assert (compare["osc_file"], compare["osc_line"], compare["osc_column"]) == ("checked.osc", 10, 8)
    assert by_id[compare["parent_id"]]["behavior_name"] == "serial"
    changes = [line for line in lines if line["timestamp"] > 0]
    timestamps = [line["timestamp"] for line in changes]
    assert timestamps == sorted(timestamps)
    final = {}
    for line in changes:                      # each line is a change of that behaviour's status
        assert final.get(line["behavior_id"], "INVALID") != line["status"], line
        final[line["behavior_id"]] = line["status"]
    assert final[compare["behavior_id"]] == "FAILURE" and final[root["behavior_id"]] == "FAILURE"
    never = [line for line in initial if line["behavior_name"] == "log"][-1]
    assert never["behavior_id"] not in final                                        # it never ran
    root_end = [line for line in changes if line["behavior_id"] == root["behavior_id"]][-1]
    assert root_end["tip_id"] == compare["behavior_id"]                            # the failing action
    assert timestamps[-1] >= 0.3                                                  # after the wait


def test_tick_log_has_one_row_per_tick_and_per_action_call(tmp_path):
    (tmp_path / "checked.osc").write_text(FAILING, encoding="utf-8")
    done = run_cli("checked.osc", "-o", "out", "--tick-log", cwd=tmp_path)
    assert done.returncode == 1, done.stdout
    assert not (tmp_path / "out/behaviors.jsonl").exists()
    ticks = rows(tmp_path / "out/tick_timing.csv")
    assert list(ticks[0]) == ["tick", "wall_ts", "timestamp", "interval_s", "duration_s", "period_s", "driver"]
    assert [int(t["tick"]) for t in ticks] == list(range(1, len(ticks) + 1)) and len(ticks) >= 4   # 0.3 s of 0.1 s
    assert ticks[0]["interval_s"] == "" and all(float(t["interval_s"]) > 0 for t in ticks[1:])
    assert {t["driver"] for t in ticks} == {"wall_loop"} and {t["period_s"] for t in ticks} == {"0.100000"}
    actions = rows(tmp_path / "out/action_timing.csv")
    setups = [a for a in actions if a["phase"] == "setup"]
    assert len(setups) == 5 and {a["tick"] for a in setups} == {""}              # before the first tick
    updates = [a for a in actions if a["phase"] == "update"]
    assert {a["behavior_name"] for a in updates} == {"log", "wait", "compare"}
    assert all(1 <= int(a["tick"]) <= len(ticks) and float(a["duration_s"]) >= 0 for a in updates)
    assert [a["status"] for a in updates if a["behavior_name"] == "compare"] == ["FAILURE"]


def test_step_based_runs_use_simulated_time_and_each_scenario_its_folder(tmp_path):
    folder = EXAMPLES / "simulation"
    done = run_cli("falling_ball.osc", "--simulation", "falling_ball.py:FallingBall", "-o", str(tmp_path / "out"),
                   "--bt-log", "--tick-log", cwd=folder)
    assert done.returncode == 0, done.stdout
    meta, *lines = records(tmp_path / "out/behaviors.jsonl")
    assert meta["clock"] == "SimulationClock" and meta["tick_period"] == 0.001
    assert abs(max(line["timestamp"] for line in lines) - 1.501) < 1e-9            # simulated seconds
    ticks = rows(tmp_path / "out/tick_timing.csv")
    assert {t["driver"] for t in ticks} == {"simulation_step"}

    two = tmp_path / "two.osc"
    two.write_text('import osc.helpers\nscenario first:\n    do serial:\n        log("1")\n'
                   'scenario second:\n    do serial:\n        log("2")\n', encoding="utf-8")
    done = run_cli(str(two), "-o", "res", "--bt-log", cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    for name in ("first", "second"):
        assert records(tmp_path / "res" / name / "behaviors.jsonl")[0]["scenario"] == name


def test_the_options_need_an_output_folder(tmp_path):
    (tmp_path / "checked.osc").write_text(FAILING, encoding="utf-8")
    for flag in ("--bt-log", "--tick-log"):
        done = run_cli("checked.osc", flag, cwd=tmp_path)
        assert done.returncode == 1
        assert done.stdout.strip() == f"error: {flag} writes into the output folder: give --output-dir"


def test_a_killed_run_leaves_every_line_written_so_far(tmp_path):
    (tmp_path / "long.osc").write_text('import osc.helpers\nscenario long:\n    do serial:\n        log("a")\n'
                                       "        wait elapsed(120s)\n", encoding="utf-8")
    (tmp_path / "out").mkdir()
    log, timing = tmp_path / "out/behaviors.jsonl", tmp_path / "out/tick_timing.csv"

    def both_written() -> bool:
        """The first action's success in the behaviour log, and a first tick's row in the timing file (it is
        written at the end of the tick, after the log line: killing in between is no lost line)."""
        text = log.read_text(encoding="utf-8") if log.exists() else ""
        return ('"behavior_name":"log","class_name"' in text and '"status":"SUCCESS"' in text
                and timing.exists() and timing.read_text(encoding="utf-8").count("\n") >= 2)

    child = subprocess.Popen([EXE, "long.osc", "-o", "out", "--bt-log", "--tick-log"], cwd=tmp_path,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while not both_written():
            assert time.monotonic() < deadline, "the logs never showed the first action's success and tick"
            time.sleep(0.05)
        os.killpg(child.pid, signal.SIGKILL)
    finally:
        child.wait(timeout=30)
    lines = records(log)                              # every line complete JSON
    assert lines[0]["scenario"] == "long" and any(line["status"] == "SUCCESS" for line in lines[1:])
    assert len(rows(tmp_path / "out/tick_timing.csv")) >= 1


def test_a_link_where_a_log_goes_is_not_followed(tmp_path):
    (tmp_path / "checked.osc").write_text(FAILING, encoding="utf-8")
    (tmp_path / "out").mkdir()
    target = tmp_path / "elsewhere.txt"
    target.write_text("keep me", encoding="utf-8")
    (tmp_path / "out/behaviors.jsonl").symlink_to(target)
    done = run_cli("checked.osc", "-o", "out", "--bt-log", cwd=tmp_path)
    assert done.returncode == 1                                   # the scenario's own failure, reported as usual
    assert "Scenario 'checked': cannot record into" in done.stdout and "Traceback" not in done.stdout
    assert "Scenario 'checked' failed: 'compare'" in done.stdout
    assert target.read_text(encoding="utf-8") == "keep me"
