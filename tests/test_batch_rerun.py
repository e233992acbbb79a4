"""--rerun-failed: a new batch of what did not pass, the report keeping the earlier passes (issue 17 item 3)."""

from __future__ import annotations

import json
import subprocess
import xml.etree.ElementTree as ET
from collections import Counter

from batch_fixtures import BIN, child_command, cli_env, ledger, run_cli, write_child, write_scenarios


def verdicts(path) -> dict[str, str]:
    out = {}
    for case in ET.parse(path).getroot().iter("testcase"):
        outcome = next((tag for tag in ("failure", "error", "skipped") if case.find(tag) is not None), "passed")
        out[case.get("name")] = outcome
    return out


def test_rerun_failed_runs_only_what_did_not_pass_and_keeps_the_rest(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"ok": "xml=pass", "flaky": "fail_first=1", "bad": "xml=fail"})
    env = cli_env(tmp_path)
    first = run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, env)
    assert first.returncode == 1
    assert verdicts(tmp_path / "results" / "test.xml") == {"ok": "passed", "flaky": "error", "bad": "failure"}

    again = run_cli(["-o", "results", "--rerun-failed"], tmp_path, env)
    assert again.returncode == 1, again.stderr
    assert "rerunning 2 job(s) that did not pass in batch 1" in again.stdout
    assert ledger(tmp_path) == Counter({"ok": 1, "flaky": 1, "bad": 2})   # flaky's first attempt ended before its ledger line
    assert verdicts(tmp_path / "results" / "test.xml") == {"ok": "passed", "flaky": "passed", "bad": "failure"}
    assert (tmp_path / "results" / "bad" / "log.1.txt").exists()         # the earlier attempt's log is kept

    (tmp_path / "in" / "bad.sce").write_text("xml=pass\n")
    fixed = run_cli(["-o", "results", "--rerun-failed"], tmp_path, env)
    assert fixed.returncode == 0, fixed.stdout + fixed.stderr
    assert ledger(tmp_path) == Counter({"ok": 1, "flaky": 1, "bad": 3})
    assert set(verdicts(tmp_path / "results" / "test.xml").values()) == {"passed"}

    nothing = run_cli(["-o", "results", "--rerun-failed"], tmp_path, env)
    assert nothing.returncode == 0
    assert "passed: nothing to rerun" in nothing.stdout
    assert ledger(tmp_path)["bad"] == 3


def test_rerun_failed_needs_an_earlier_batch_and_takes_no_input(tmp_path):
    env = cli_env(tmp_path)
    none = run_cli(["-o", "results", "--rerun-failed"], tmp_path, env)
    assert none.returncode == 1 and "nothing to rerun" in none.stderr
    mixed = run_cli(["-i", "in", "-o", "results", "--rerun-failed"], tmp_path, env)
    assert mixed.returncode == 2 and "--rerun-failed takes only -o" in mixed.stderr


#: Per rerun: the files fixed before it, the jobs it runs, and the verdicts test.xml then holds (issue 31 item 5).
RERUNS = [
    ({"d"}, {"d", "e", "f"}, {"a": "passed", "b": "passed", "c": "passed", "d": "passed", "e": "failure",
                              "f": "failure"}),
    ({"e"}, {"e", "f"}, {"a": "passed", "b": "passed", "c": "passed", "d": "passed", "e": "passed",
                         "f": "failure"}),
    (set(), {"f"}, {"a": "passed", "b": "passed", "c": "passed", "d": "passed", "e": "passed", "f": "failure"}),
    ({"f"}, {"f"}, dict.fromkeys("abcdef", "passed")),
]


def test_every_rerun_keeps_the_latest_verdict_of_every_job_of_the_folder(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {**dict.fromkeys("abc", "xml=pass"), **dict.fromkeys("def", "xml=fail")})
    env = cli_env(tmp_path)
    first = run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, env)
    assert first.returncode == 1
    runs = ledger(tmp_path)
    for number, (fixed, ran, expected) in enumerate(RERUNS, start=1):
        for name in fixed:
            (tmp_path / "in" / f"{name}.sce").write_text("xml=pass\n")
        again = run_cli(["-o", "results", "--rerun-failed"], tmp_path, env)
        assert again.returncode == (0 if set(expected.values()) == {"passed"} else 1), again.stdout + again.stderr
        runs.update(ran)
        assert ledger(tmp_path) == runs, f"rerun {number} ran other jobs than {sorted(ran)}"
        assert verdicts(tmp_path / "results" / "test.xml") == expected, f"after rerun {number}"
        failed = sum(1 for v in expected.values() if v != "passed")
        assert f"6 job(s): {6 - failed} passed" in again.stdout, again.stdout
    nothing = run_cli(["-o", "results", "--rerun-failed"], tmp_path, env)
    assert nothing.returncode == 0 and "passed: nothing to rerun" in nothing.stdout


def test_the_report_subcommand_of_a_rerun_holds_the_whole_folder(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"ok": "xml=pass", "bad": "xml=fail", "worse": "xml=error"})
    env = cli_env(tmp_path)
    run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, env)
    (tmp_path / "in" / "bad.sce").write_text("xml=pass\n")
    for _ in range(2):
        run_cli(["-o", "results", "--rerun-failed"], tmp_path, env)
    done = run_cli(["report", "-o", "merged.xml"], tmp_path, env)
    assert done.returncode == 1, done.stdout + done.stderr
    assert verdicts(tmp_path / "merged.xml") == {"ok": "passed", "bad": "passed", "worse": "error"}
    root = ET.parse(tmp_path / "merged.xml").getroot()
    assert (root.get("tests"), root.get("errors"), root.get("failures")) == ("3", "1", "0")
    coverage = subprocess.run([str(BIN / "scenario_coverage"), "json", "--store", "sqlite:///.scenario_store.db",
                               "results"], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert coverage.returncode == 0, coverage.stderr
    document = json.loads(coverage.stdout)
    assert document["source"].startswith("batches 1, 2, 3 in ") and document["complete"] is True
    assert (document["runs"]["total"], document["runs"]["passed"]) == (3, 2)
