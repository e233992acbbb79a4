"""Crash and interrupt safety: kill -9 or Ctrl-C in the middle of a batch, then ``--resume``."""

from __future__ import annotations

import os
import signal
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from batch_fixtures import (
    alive,
    child_command,
    cli_env,
    ledger,
    run_cli,
    start_cli,
    watchdog_of,
    write_child,
    write_scenarios,
)

from store.queue import QueueStore
from store.states import FINAL, JobState


def _suite_names(path: Path) -> list[str]:
    return [s.get("name") for s in ET.parse(path).getroot().iter("testsuite")]


def _wait_for_ledger(tmp_path: Path, count: int, proc, timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while sum(ledger(tmp_path).values()) < count:
        assert proc.poll() is None, proc.stdout.read()
        assert time.monotonic() < deadline, "the batch made no progress"
        time.sleep(0.02)


def _wait_for_a_running_job(tmp_path: Path, proc, timeout: float = 30) -> None:
    deadline = time.monotonic() + timeout
    while not any(j.status is JobState.RUNNING and j.started_at and time.time() - j.started_at < 0.5
                  for j in _store_jobs(tmp_path)):
        assert proc.poll() is None and time.monotonic() < deadline, "no job was running"
        time.sleep(0.02)


def _store_jobs(tmp_path: Path):
    store = QueueStore.open(f"sqlite:///{tmp_path / '.scenario_store.db'}")
    try:
        batch = store.latest_batch()
        return store.jobs(batch.id)
    finally:
        store.close()


@pytest.mark.slow
def test_kill_9_mid_batch_then_resume_runs_each_job_once(tmp_path):
    names = [f"job{i:03d}" for i in range(200)]
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {n: "sleep=0.01" for n in names})
    env = cli_env(tmp_path)
    args = ["-i", "in", "-o", "results", "-j", "4", "--", *child_command(child)]
    proc = start_cli(args, tmp_path, env)
    _wait_for_ledger(tmp_path, 60, proc)
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=10)

    before = _store_jobs(tmp_path)
    finished_before = {j.name for j in before if j.status in FINAL}
    assert 40 <= len(finished_before) < 200
    assert any(j.status is JobState.QUEUED for j in before)
    held = {j.name for j in before if j.status is JobState.RUNNING and j.child_pid is None}
    assert held, "no job was held without a recorded start"

    resumed = run_cli(["-o", "results", "--resume", "-j", "4", "--", *child_command(child)], tmp_path, env)
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr

    assert sorted(_suite_names(tmp_path / "results" / "test.xml")) == names     # each exactly once
    runs = ledger(tmp_path)
    assert set(runs) == set(names)
    assert all(runs[n] == 1 for n in finished_before), "a finished job ran again"
    after = _store_jobs(tmp_path)
    assert all(j.status is JobState.PASSED for j in after)
    assert all(j.attempts == 1 for j in after if j.name in finished_before)
    assert all(j.lost == 0 for j in after if j.name in held), "a job that never started was charged"


def test_ctrl_c_cancels_writes_partial_report_and_resume_completes(tmp_path):
    names = [f"s{i:02d}" for i in range(12)]
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {n: "sleep=0.8" for n in names})
    env = cli_env(tmp_path)
    proc = start_cli(["-i", "in", "-o", "results", "-j", "2", "--grace", "2", "--",
                      *child_command(child)], tmp_path, env)
    _wait_for_ledger(tmp_path, 3, proc)
    _wait_for_a_running_job(tmp_path, proc)     # not in the gap between one job's end and the next one's start
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 130, out
    assert "--resume" in out

    jobs = _store_jobs(tmp_path)
    finished = [j.name for j in jobs if j.status in FINAL]
    cancelled = [j.name for j in jobs if j.status is JobState.CANCELLED]
    assert cancelled, "the running jobs are marked cancelled"
    assert not any(j.status is JobState.RUNNING for j in jobs)
    assert _suite_names(tmp_path / "results" / "test.xml") == names          # the unfinished ones count too

    resumed = run_cli(["-o", "results", "--resume", "-j", "2", "--", *child_command(child)], tmp_path, env)
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert _suite_names(tmp_path / "results" / "test.xml") == names
    runs = ledger(tmp_path)
    assert all(runs[n] == 1 for n in finished)
    store = QueueStore.open(f"sqlite:///{tmp_path / '.scenario_store.db'}")
    try:
        for job in store.jobs(store.latest_batch().id):
            if job.name not in cancelled:
                continue
            first = store.attempts(job.id)[0]
            assert first["outcome"] == "cancelled" and job.attempts == 2
            if first["reason"] != "cancelled before it started":      # the cancelled attempt's log is kept
                assert (tmp_path / "results" / job.name / "log.1.txt").exists()
    finally:
        store.close()


def _cases(path: Path) -> dict[str, tuple[str, str | None, str | None]]:
    """Per suite (job): its testcase's outcome (passed, error, failure, skipped), type and message."""
    out = {}
    for suite in ET.parse(path).getroot().iter("testsuite"):
        for case in suite.iter("testcase"):
            problem = next((e for e in case if e.tag in ("error", "failure", "skipped")), None)
            if problem is None:
                out[suite.get("name")] = ("passed", None, None)
            else:
                out[suite.get("name")] = (problem.tag, problem.get("type"), problem.get("message"))
    return out


@pytest.mark.slow
def test_report_written_at_ctrl_c_counts_every_job_and_resume_replaces_it(tmp_path):
    names = [f"s{i}" for i in range(6)]
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {n: "sleep=1.5" for n in names})
    env = cli_env(tmp_path)
    proc = start_cli(["-i", "in", "-o", "results", "--grace", "1", "--", *child_command(child)], tmp_path, env)
    _wait_for_ledger(tmp_path, 1, proc)                           # s0 finished, s1 is starting
    log = tmp_path / "results" / "s1" / "log.txt"
    deadline = time.monotonic() + 20
    while not (log.exists() and "start s1" in log.read_text()):
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 130, out

    report = tmp_path / "results" / "test.xml"
    root = ET.parse(report).getroot()
    # a CI reading only the XML must not see a clean pass: the whole batch is counted
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("6", "0", "1")
    assert sum(int(s.get("skipped")) for s in root.iter("testsuite")) == 4
    cases = _cases(report)
    assert list(cases) == names
    assert cases["s0"][0] == "passed"
    assert cases["s1"] == ("error", "cancelled", "interrupted (Ctrl-C); run again with --resume")
    for name in names[2:]:
        assert cases[name] == ("skipped", None, "not run: the batch was interrupted; --resume runs it")
    numbers = [line.split("]")[0] + "]" for line in out.splitlines() if line.startswith("[")]
    assert numbers == ["[1/6]", "[2/6]"], out                     # the cancelled job has its own number

    resumed = run_cli(["-o", "results", "--resume"], tmp_path, env)
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    root = ET.parse(report).getroot()
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("6", "0", "0")
    assert sum(int(s.get("skipped")) for s in root.iter("testsuite")) == 0
    assert all(outcome == "passed" for outcome, _, _ in _cases(report).values())
    assert [line.split("]")[0] + "]" for line in resumed.stdout.splitlines() if line.startswith("[")] == \
        ["[2/6]", "[3/6]", "[4/6]", "[5/6]", "[6/6]"]
    assert ledger(tmp_path) == {n: 1 for n in names}


def test_resume_of_a_finished_batch_rewrites_the_report(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"a": "", "b": "xml=fail"})
    env = cli_env(tmp_path)
    assert run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, env).returncode == 1
    (tmp_path / "results" / "test.xml").unlink()
    again = run_cli(["-o", "results", "--resume"], tmp_path, env)
    assert again.returncode == 1
    assert _suite_names(tmp_path / "results" / "test.xml") == ["a", "b"]
    assert ledger(tmp_path) == {"a": 1, "b": 1}
    other = run_cli(["-o", "results", "--resume", "--", "true", "{SCENARIO}", "{OUTPUT_DIR}"], tmp_path, env)
    assert other.returncode == 1 and "different command" in other.stderr


def test_resume_ends_the_process_group_a_killed_runner_and_watchdog_left_behind(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"orphan": "grandchild=1\nslow_first=60"})
    env = cli_env(tmp_path)
    proc = start_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, env)
    job_dir = tmp_path / "results" / "orphan"
    deadline = time.monotonic() + 20
    while not ((job_dir / "child.pid").exists() and (job_dir / "grandchild.pid").exists()):
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.02)
    child_pid = int((job_dir / "child.pid").read_text())
    while not any(j.child_pid == child_pid for j in _store_jobs(tmp_path)):   # the store names the group to end
        assert time.monotonic() < deadline and proc.poll() is None, "the child's pid never reached the store"
        time.sleep(0.02)
    # the runner and its watchdog both die at once (as when the OOM killer takes the whole group)
    watchdog = watchdog_of(proc.pid)
    proc.send_signal(signal.SIGKILL)
    os.kill(watchdog, signal.SIGKILL)
    proc.communicate(timeout=10)
    orphans = [int((job_dir / name).read_text()) for name in ("child.pid", "grandchild.pid")]
    assert all(alive(pid) for pid in orphans)                    # nobody ended them yet

    start = time.monotonic()
    resumed = run_cli(["-o", "results", "--resume"], tmp_path, env, timeout=60)
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert time.monotonic() - start < 50                          # the orphaned first attempt would sleep 60 s
    deadline = time.monotonic() + 20
    while any(alive(pid) for pid in orphans):
        assert time.monotonic() < deadline, "the orphaned process group survived --resume"
        time.sleep(0.05)
    assert ledger(tmp_path) == {"orphan": 1}
    assert _suite_names(tmp_path / "results" / "test.xml") == ["orphan"]


def test_resume_refuses_options_that_differ_from_the_batch(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"a": ""})
    write_scenarios(tmp_path / "other", {"a": ""})
    env = cli_env(tmp_path)
    first = run_cli(["-i", "in", "-o", "results", "--timeout", "30", "--retries", "1", "--post-run", "true",
                     "--", *child_command(child)], tmp_path, env)
    assert first.returncode == 0, first.stdout + first.stderr
    differing = run_cli(["-i", "other", "-o", "results", "--resume", "--timeout", "60", "--retries", "1",
                         "--post-run", "echo", "-r"], tmp_path, env)
    assert differing.returncode == 1, differing.stdout + differing.stderr
    message = differing.stderr.strip()
    assert len(message.splitlines()) == 1 and "Traceback" not in message
    for part in ("--timeout 60 (the batch has 30)", "--post-run echo (the batch has true)",
                 "--ignore-process-return-value True (the batch has False)",
                 f"-i other (the batch has {tmp_path / 'in'})"):
        assert part in message, message
    assert "--retries" not in message                           # the same value is no difference
    same = run_cli(["-i", "in", "-o", "results", "--resume", "--timeout", "30", "--retries", "1",
                    "--post-run", "true"], tmp_path, env)
    assert same.returncode == 0, same.stdout + same.stderr
    assert run_cli(["-o", "results", "--resume", "-j", "2"], tmp_path, env).returncode == 0
    assert ledger(tmp_path) == {"a": 1}
