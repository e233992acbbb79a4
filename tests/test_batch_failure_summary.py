"""A batch ends with one line per job that did not pass: which variant, why, where its log is (issue 22 item 1)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from batch_fixtures import child_command, cli_env, run_cli, write_child, write_scenarios

BIN = Path(sys.executable).parent
SCENARIO = """import osc.helpers
scenario gap_check:
    gap: float = 1.0 with:
        keep(it in [0.5, 2.0])
    do serial:
        compare(gap, ">", 1.0)
"""


def test_failed_variants_are_listed_with_values_reason_and_log(tmp_path):
    (tmp_path / "gap.osc").write_text(SCENARIO)
    env = dict(os.environ, NO_COLOR="1")
    env.pop("SCENARIO_STORE", None)
    subprocess.run([str(BIN / "scenario_variation"), "gap.osc"], cwd=tmp_path, env=env, check=True, capture_output=True)
    done = subprocess.run([str(BIN / "scenario_batch_execution"), "-i", "out", "-o", "results"], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    lines = done.stdout.splitlines()
    at = lines.index("--- 1 job(s) did not pass ---")
    assert lines[at + 1] == (f"FAILED   gap0[gap=0.5] - 'compare' at {tmp_path / 'gap.osc'}:6:9 "
                             f"({tmp_path / 'out' / 'gap0.sce'}:18:9) failed: "
                             f"0.5 > 1.0 is False  (log: {tmp_path / 'results' / 'gap0' / 'log.txt'})")
    assert lines[at + 2].startswith("batch 1: 2 job(s): 1 passed, 1 failed")
    status = subprocess.run([str(BIN / "scenario_batch_execution"), "status", "--list", "failed", "--json"],
                            cwd=tmp_path, env=env, capture_output=True, text=True)
    document = json.loads(status.stdout)
    assert document["counts"]["failed"] == 1 and document["counts"]["passed"] == 1
    assert [(i["name"], i["status"]) for i in document["not_passed"]] == [("gap0[gap=0.5]", "failed")]
    assert "0.5 > 1.0 is False" in document["not_passed"][0]["reason"]


def test_timeouts_and_errors_say_why_and_names_are_escaped(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"slow": "sleep=30", "crash": "xml=none\nexit=3", "ok": "xml=pass",
                                      "esc\x1b[2J": "xml=fail"})
    done = run_cli(["-i", "in", "-o", "results", "-j", "2", "--timeout", "1", "--", *child_command(child)], tmp_path,
                   cli_env(tmp_path))
    assert done.returncode == 1
    summary = done.stdout[done.stdout.index("--- 3 job(s) did not pass ---"):]
    assert "\x1b" not in done.stdout
    assert "FAILED   esc\\x1b[2J - it failed" in summary
    assert "TIMEOUT  slow - timed out after 1 s" in summary
    assert "ERROR    crash - " in summary and "exit code 3" in summary
    assert "ok" not in summary.split("\n", 1)[1].split("batch ")[0].replace("(log", "")


def test_variant_values_reach_the_report_whatever_store_ran_the_batch(tmp_path):
    """Variation recorded in one store, the batch run with another: the .sce header names the values (item 2)."""
    import xml.etree.ElementTree as ET

    (tmp_path / "gap.osc").write_text(SCENARIO)
    env = dict(os.environ, NO_COLOR="1")
    env.pop("SCENARIO_STORE", None)
    subprocess.run([str(BIN / "scenario_variation"), "gap.osc", "--store", f"sqlite:///{tmp_path / 'a.db'}"],
                   cwd=tmp_path, env=env, check=True, capture_output=True)
    subprocess.run([str(BIN / "scenario_batch_execution"), "-i", "out", "-o", "results", "--store",
                    f"sqlite:///{tmp_path / 'b.db'}"], cwd=tmp_path, env=env, capture_output=True, timeout=120)
    suites = {s.get("name"): s for s in ET.parse(tmp_path / "results" / "test.xml").getroot().iter("testsuite")}
    properties = {p.get("name"): p.get("value") for p in suites["gap1"].iter("property")}
    assert properties["variation.gap_check.gap"] == "2.0"


def test_report_json_gives_counts_and_failures(tmp_path):
    (tmp_path / "gap.osc").write_text(SCENARIO)
    env = dict(os.environ, NO_COLOR="1")
    env.pop("SCENARIO_STORE", None)
    subprocess.run([str(BIN / "scenario_variation"), "gap.osc"], cwd=tmp_path, env=env, check=True, capture_output=True)
    subprocess.run([str(BIN / "scenario_batch_execution"), "-i", "out", "-o", "results"], cwd=tmp_path, env=env,
                   capture_output=True, timeout=120)
    done = subprocess.run([str(BIN / "scenario_batch_execution"), "report", "--json", "-o", "again.xml"], cwd=tmp_path,
                          env=env, capture_output=True, text=True)
    assert done.returncode == 1
    document = json.loads(done.stdout)
    assert document["counts"]["passed"] == 1 and document["counts"]["failed"] == 1 and document["exit_code"] == 1
    assert [i["name"] for i in document["not_passed"]] == ["gap0[gap=0.5]"]
    assert (tmp_path / "again.xml").is_file()
