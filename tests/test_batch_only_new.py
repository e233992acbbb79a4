"""``--only-new`` end to end (issue 31 item 8): a sampler tops up its variants, the batch runs only the new
ones, and the folder's report and coverage hold the old and the new runs; through the real CLIs, in a pipe."""

from __future__ import annotations

import json
import subprocess
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

from batch_fixtures import BIN, child_command, cli_env, ledger, run_cli, write_child, write_scenarios
from cli_support import SAMPLED_DRIVE as DRIVE
from cli_support import run_variation


def vary(cwd: Path, *args: str) -> str:
    done = run_variation(cwd, "drive.osc", "--strategy", "random", "--seed", "11", *args)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def batch(cwd: Path, *args: str) -> subprocess.CompletedProcess:
    return run_cli(["-i", "out", "-o", "results", *args], cwd, cli_env(cwd))


def case_names(cwd: Path) -> list[str]:
    return sorted(case.get("name").split("[")[0] for case in ET.parse(cwd / "results" / "test.xml").iter("testcase"))


def test_the_batch_after_a_top_up_runs_only_the_new_variants_and_reports_them_all(tmp_path):
    (tmp_path / "drive.osc").write_text(DRIVE)
    vary(tmp_path, "--samples", "5")
    first = batch(tmp_path)
    assert first.returncode == 0, first.stdout + first.stderr
    assert "batch 1: 5 job(s): 5 passed" in first.stdout
    logs = {p.parent.name: p.read_bytes() for p in (tmp_path / "results").glob("drive*/log.txt")}

    assert "wrote 3 new scenario file(s)" in vary(tmp_path, "--samples", "8", "--only-new")
    second = batch(tmp_path, "--only-new")
    assert second.returncode == 0, second.stdout + second.stderr
    assert "batch 2: 3 new scenario file(s); 5 already have a verdict in batch 1 (the report keeps theirs)" \
        in second.stdout
    ran = sorted(line.split()[2] for line in second.stdout.splitlines() if line.startswith("[") and "passed" in line)
    assert ran == ["drive5", "drive6", "drive7"]
    assert "batch 2: 8 job(s): 8 passed" in second.stdout
    assert {p.parent.name: p.read_bytes() for p in (tmp_path / "results").glob("drive[0-4]/log.txt")} == logs
    assert not list((tmp_path / "results").glob("*/log.1.txt")), "an earlier variant ran again"
    assert case_names(tmp_path) == [f"drive{i}" for i in range(8)]

    report = subprocess.run([str(BIN / "scenario_coverage"), "json", "results"], cwd=tmp_path, capture_output=True,
                            text=True, env=cli_env(tmp_path))
    assert report.returncode == 0, report.stderr
    document = json.loads(report.stdout)
    assert document["complete"] is True and document["runs"]["total"] == 8 and document["runs"]["passed"] == 8
    lane = next(item for item in document["items"] if item["name"] == "input:drive.lane")
    assert sum(bucket["hits"] for bucket in lane["buckets"]) == 8
    stored = subprocess.run([str(BIN / "scenario_coverage"), "json", "--store", "sqlite:///.scenario_store.db",
                             "results"], cwd=tmp_path, capture_output=True, text=True, env=cli_env(tmp_path))
    assert stored.returncode == 0, stored.stderr
    from_store = json.loads(stored.stdout)
    assert from_store["source"].startswith("batches 1, 2 in ")
    assert from_store["runs"] == document["runs"]

    nothing = batch(tmp_path, "--only-new")
    assert nothing.returncode == 5, nothing.stdout + nothing.stderr
    assert "nothing new: each of the 8 scenario file(s) of -i has a verdict in" in nothing.stdout
    assert case_names(tmp_path) == [f"drive{i}" for i in range(8)]


def test_only_new_counts_a_changed_file_as_new_and_a_folder_without_batch_runs_everything(tmp_path):
    (tmp_path / "drive.osc").write_text(DRIVE)
    vary(tmp_path, "--samples", "3")
    first = batch(tmp_path, "--only-new")
    assert first.returncode == 0 and "batch 1: 3 job(s): 3 passed" in first.stdout, first.stdout + first.stderr
    changed = tmp_path / "out" / "drive1.sce"
    changed.write_text(changed.read_text().replace('log("x")', 'log("y")'))
    again = batch(tmp_path, "--only-new")
    assert "batch 2: 1 new scenario file(s); 2 already have a verdict in batch 1" in again.stdout, again.stdout
    assert (tmp_path / "results" / "drive1" / "log.1.txt").exists()
    assert case_names(tmp_path) == ["drive0", "drive1", "drive2"]


def test_only_new_goes_with_neither_resume_nor_rerun_failed(tmp_path):
    for other in ("--resume", "--rerun-failed"):
        refused = run_cli(["-i", "out", "-o", "results", "--only-new", other], tmp_path, cli_env(tmp_path))
        assert refused.returncode == 2, refused.stderr
        assert "Traceback" not in refused.stderr
    assert "--only-new starts a batch of the new files of -i: it does not go with --resume" in \
        run_cli(["-o", "results", "--only-new", "--resume"], tmp_path, cli_env(tmp_path)).stderr


def test_a_top_up_batch_still_reports_and_counts_the_folders_earlier_failure(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"ok": "xml=pass", "bad": "xml=fail"})
    env = cli_env(tmp_path)
    assert run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, env).returncode == 1
    write_scenarios(tmp_path / "in", {"new": "xml=pass"})
    top_up = run_cli(["-i", "in", "-o", "results", "--only-new", "--", *child_command(child)], tmp_path, env)
    assert top_up.returncode == 1, top_up.stdout + top_up.stderr
    assert ledger(tmp_path) == Counter({"ok": 1, "bad": 1, "new": 1})
    lines = top_up.stdout.splitlines()
    at = lines.index("--- 1 job(s) did not pass ---")
    assert lines[at + 1].startswith("FAILED   bad - it failed")
    assert lines[at + 2].startswith("batch 2: 3 job(s): 2 passed, 1 failed; report ")
    report = ET.parse(tmp_path / "results" / "test.xml").getroot()
    assert (report.get("tests"), report.get("failures")) == ("3", "1")
