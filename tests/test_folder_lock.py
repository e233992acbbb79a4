"""One writer per output folder (issue 21 item 2): a second batch or variation run is refused, or waits."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

from batch_fixtures import CLI, child_command, cli_env, ledger, run_cli, write_child, write_scenarios

ROOT = Path(__file__).resolve().parents[1]


def start_holder(tmp_path: Path, seconds: float) -> subprocess.Popen:
    """A real batch writing into results/ for about ``seconds``."""
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"slow": f"sleep={seconds}"})
    holder = subprocess.Popen([CLI, "-i", "in", "-o", "results", "--", *child_command(child)], cwd=tmp_path,
                              env=cli_env(tmp_path), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + 30
    while not (tmp_path / "results" / "slow" / "log.txt").exists():      # the first job has started
        assert time.monotonic() < deadline and holder.poll() is None, holder.communicate()[0]
        time.sleep(0.05)
    return holder


def test_a_second_batch_on_the_same_folder_is_refused_and_runs_nothing(tmp_path):
    holder = start_holder(tmp_path, 3)
    child = tmp_path / "child.py"
    second = run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, cli_env(tmp_path))
    assert second.returncode == 1
    assert "results/ is being written by scenario_batch_execution (pid " in second.stderr
    assert "pass --wait" in second.stderr
    holder.communicate(timeout=60)
    assert holder.returncode == 0
    assert ledger(tmp_path) == {"slow": 1}                  # every job ran exactly once


def test_with_wait_the_second_batch_runs_after_the_first(tmp_path):
    holder = start_holder(tmp_path, 2)
    child = tmp_path / "child.py"
    second = run_cli(["-i", "in", "-o", "results", "--wait", "--", *child_command(child)], tmp_path,
                     cli_env(tmp_path))
    holder.communicate(timeout=60)
    assert second.returncode == 0, second.stderr
    assert "waiting for" in second.stderr
    assert ledger(tmp_path) == {"slow": 2}                  # one run per batch, one after the other


def test_variation_into_a_folder_being_written_is_refused_and_writes_nothing(tmp_path):
    holder = start_holder(tmp_path, 3)
    (tmp_path / "v.osc").write_text("import osc.helpers\nscenario v:\n    do serial:\n        log() with:\n"
                                    "            keep(it.msg in ['a', 'b'])\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT), NO_COLOR="1")
    env.pop("SCENARIO_STORE", None)
    done = subprocess.run([sys.executable, "-m", "cli.scenario_variation", "v.osc", "-o", "results"], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 1
    assert "is being written by scenario_batch_execution" in done.stderr and "nothing was written" in done.stderr
    assert not list((tmp_path / "results").glob("*.sce"))
    waited = subprocess.run([sys.executable, "-m", "cli.scenario_variation", "v.osc", "-o", "results", "--wait"],
                            cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    assert waited.returncode == 0, waited.stderr
    assert sorted(p.name for p in (tmp_path / "results").glob("*.sce")) == ["v0.sce", "v1.sce"]
    holder.communicate(timeout=60)


def test_a_killed_holder_leaves_no_stale_lock(tmp_path):
    holder = start_holder(tmp_path, 30)
    holder.kill()
    holder.communicate(timeout=30)
    child = tmp_path / "child.py"
    second = run_cli(["-i", "in", "-o", "results", "--timeout", "5", "--", *child_command(child)], tmp_path,
                     cli_env(tmp_path, BATCH_LEDGER=str(tmp_path / "l2.txt")))
    assert "is being written" not in second.stderr
