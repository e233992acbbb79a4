"""The fork server started early (issue 34): the command line launches it before it reads the store and
the inputs, and the worker adopts it; a run that needs none leaves nothing behind.
"""

from __future__ import annotations

import os
import signal
import sqlite3
import tempfile
import time
from pathlib import Path

from batch_fixtures import alive, cli_env, marked, run_cli, server_of, start_cli

from executor.batch.builtin_runner import ForkServer
from executor.batch.hand_over import HandOver
from executor.batch.worker_server import fork_server_environment, start_early

HANG = "import osc.helpers\n\nscenario hang{n}:\n    do serial:\n        wait elapsed(60s)\n        emit end\n"


def started_at(pid: int) -> float:
    """When process ``pid`` started, in seconds since the epoch, to a clock tick (``/proc``'s start time
    counts from boot; ``btime`` would be a whole second off)."""
    with open(f"/proc/{pid}/stat") as handle:
        ticks = int(handle.read().rsplit(")", 1)[1].split()[19])
    boot = time.time() - time.clock_gettime(time.CLOCK_BOOTTIME)
    return boot + ticks / os.sysconf("SC_CLK_TCK")


def store_state(path: Path) -> tuple[int, tuple[float] | None]:
    """Jobs started, and the batch's creation time, as far as the store says yet (read-only: never made here)."""
    try:
        with sqlite3.connect(f"file:{path}?mode=ro", uri=True) as conn:
            running = conn.execute("SELECT COUNT(*) FROM jobs WHERE status = 'running' "
                                   "AND started_at IS NOT NULL").fetchone()[0]
            return running, conn.execute("SELECT created_at FROM batches").fetchone()
    except sqlite3.OperationalError:             # not made yet, or its tables not yet
        return 0, None


def test_the_command_line_starts_the_fork_server_before_it_reads_the_store(tmp_path):
    (tmp_path / "in").mkdir()
    for n in range(2):
        (tmp_path / "in" / f"hang{n}.osc").write_text(HANG.format(n=n))
    runner = start_cli(["-i", "in", "-o", "res", "-j", "1"], tmp_path, cli_env(tmp_path))
    deadline = time.monotonic() + 60
    while True:
        assert time.monotonic() < deadline and runner.poll() is None, "the batch starts its first job"
        running, created = store_state(tmp_path / ".scenario_store.db")
        server = server_of(runner.pid)
        if running and server is not None:
            break
        time.sleep(0.05)
    assert created is not None and started_at(server) < created[0]   # launched before the batch was made
    runner.send_signal(signal.SIGINT)
    runner.communicate(timeout=30)
    assert runner.returncode == 130
    assert not alive(server)


def test_a_run_with_nothing_to_run_leaves_no_server_behind(tmp_path):
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "hang0.osc").write_text(HANG.format(n=0).replace("wait elapsed(60s)", "wait elapsed(0.1s)"))
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = cli_env(tmp_path, TMPDIR=str(scratch))
    assert run_cli(["-i", "in", "-o", "res"], tmp_path, env).returncode == 0
    again = run_cli(["-i", "in", "-o", "res", "--only-new"], tmp_path, env)   # each file has a verdict: none runs
    assert "nothing new" in again.stdout, again.stdout + again.stderr
    assert marked(f"TMPDIR={scratch}") == []         # the server launched early is gone
    assert list(scratch.iterdir()) == []             # and so is its scratch folder


def test_kill_9_of_a_command_waiting_for_its_folder_leaves_neither_its_server_nor_its_scratch(tmp_path):
    # the server is launched before the worker (and its watchdog) exists: killed then, the command can
    # remove nothing, and the server, finding its runner gone, must end and remove its folder itself
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "hang0.osc").write_text(HANG.format(n=0))
    holder = start_cli(["-i", "in", "-o", "res", "-j", "1"], tmp_path, cli_env(tmp_path))
    scratch = tmp_path / "waiting_tmp"
    scratch.mkdir()
    waiting = None
    try:
        deadline = time.monotonic() + 60
        while store_state(tmp_path / ".scenario_store.db")[0] == 0:     # the first batch holds -o res
            assert time.monotonic() < deadline and holder.poll() is None, "the first batch runs"
            time.sleep(0.05)
        waiting = start_cli(["-i", "in", "-o", "res", "--wait"], tmp_path, cli_env(tmp_path, TMPDIR=str(scratch)))
        while not marked(f"TMPDIR={scratch}") or not any(scratch.iterdir()):   # its server, and its scratch
            assert time.monotonic() < deadline and waiting.poll() is None, "the waiting command starts its server"
            time.sleep(0.05)
        time.sleep(1.0)                                  # (the server done preloading, or not: either way)
        waiting.send_signal(signal.SIGKILL)
        waiting.communicate(timeout=10)
        killed_at = time.monotonic()
        while marked(f"TMPDIR={scratch}") or any(scratch.iterdir()):
            assert time.monotonic() - killed_at < 10, (marked(f"TMPDIR={scratch}"), list(scratch.iterdir()))
            time.sleep(0.05)
    finally:
        for process in (holder, waiting):
            if process is not None and process.poll() is None:
                process.send_signal(signal.SIGINT)
                process.communicate(timeout=30)


def test_the_worker_adopts_an_early_server_launched_as_it_would_start_one(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    early = start_early(2)
    assert early is not None
    told: list[str] = []
    hand_over = HandOver(early.identity.id, 2, ahead_allowed=False, on_scratch=told.append, early=early.server)
    try:
        assert hand_over.launcher() is early.server and early.server.alive
        assert told == [early.server.scratch]        # the watchdog learns of its scratch folder
    finally:
        hand_over.close()
    assert not early.server.alive and list(tmp_path.iterdir()) == []


def test_an_early_server_launched_otherwise_is_closed_and_a_new_one_started(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    other = ForkServer(fork_server_environment("another-runner"), limit=2).launch()
    hand_over = HandOver("this-runner", 2, ahead_allowed=False, early=other)
    try:
        server = hand_over.launcher()
        assert server is not other and server.alive
        assert server.environment["SCENARIO_BATCH_RUNNER"] == "this-runner"
        assert other.proc is None and not other.alive                   # closed, its process reaped
    finally:
        hand_over.close()
    assert [p for p in Path(tmp_path).iterdir()] == []
