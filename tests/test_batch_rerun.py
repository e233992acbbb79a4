"""--rerun-failed: a new batch of what did not pass, the report keeping the earlier passes (issue 17 item 3)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections import Counter

from batch_fixtures import child_command, cli_env, ledger, run_cli, write_child, write_scenarios


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
