"""Attempts the worker's loop drives without a thread (executor.batch.loop_run), each alone with real children.

A launched command (SpawnedRun) is started with posix_spawn and its end read from its process descriptor;
the loop here is the worker's own wait (Inbox.wait on the run's descriptor and its deadlines). The built-in
kind (ForkedRun) is driven through the real CLI in test_batch_builtin.py; here only what it makes of the
server's replies.
"""

from __future__ import annotations

import os
import subprocess
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path

import pytest

from executor.batch.forked_run import ForkedRun
from executor.batch.inbox import Inbox
from executor.batch.job_run import Done, Started
from executor.batch.loop_run import MAX_LAG, moment
from executor.batch.progress import PlainReporter
from executor.batch.spawned_run import SpawnedRun, loop_can_spawn
from executor.batch.worker import Worker, WorkerSettings
from store.jobs import Batch, BatchOptions, JobSpec, WorkerIdentity
from store.queue import QueueStore
from store.states import NOT_STARTED_REASON, JobState

pytestmark = pytest.mark.skipif(not loop_can_spawn(), reason="no posix_spawn or pidfd_open here")

#: A job writing a passing one-testcase report into its folder.
PASSING = ('echo "<testsuite><testcase name=\\"t\\"/></testsuite>" > "$2/test.xml"',)


@pytest.fixture
def store(tmp_path: Path) -> Iterator[QueueStore]:
    opened = QueueStore.open(f"sqlite:///{tmp_path / 'store.db'}")
    yield opened
    opened.close()


def _run(store: QueueStore, tmp_path: Path, script: str, **options: object) -> SpawnedRun:
    """A claimed job whose command is ``sh -c script sh {SCENARIO} {OUTPUT_DIR}``, its folder made."""
    batch: Batch = store.create_batch(
        mode="local", input_dir=str(tmp_path), output_dir=str(tmp_path / "res"), host="h",
        command=("sh", "-c", script, "sh", "{SCENARIO}", "{OUTPUT_DIR}"), options=BatchOptions(**options),
        specs=[JobSpec("j0", str(tmp_path / "j0.sce"), "0" * 64, "x")])
    (job,) = store.claim(WorkerIdentity.current(), limit=1, batch_id=batch.id)
    folder = tmp_path / "res" / job.name
    folder.mkdir(parents=True)
    return SpawnedRun(job, batch, folder, job.scenario_path, environment={})


def inbox_put(inbox: Inbox, run: SpawnedRun):
    """What the worker does when the run's descriptor is readable: its events into the inbox."""
    return lambda: [inbox.put(event) for event in run.on_readable()]


def living_members(pgid: int, within: float = 5.0) -> list[int]:
    """Processes of group ``pgid`` still alive after up to ``within`` seconds (SIGKILL is delivered when
    the process next runs; a killed orphan may stay a zombie until init reaps it)."""
    end = time.monotonic() + within
    while True:
        found = _members(pgid)
        if not found or time.monotonic() > end:
            return found
        time.sleep(0.02)


def _members(pgid: int) -> list[int]:
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                fields = Path(f"/proc/{entry}/stat").read_bytes().rsplit(b")", 1)[1].split()
            except OSError:
                continue
            if int(fields[2]) == pgid and fields[0] != b"Z":
                found.append(int(entry))
    return found


class Driven:
    """How a run went under the loop: its events and how many times the loop waited."""

    def __init__(self) -> None:
        self.started: list[Started] = []
        self.done: list[Done] = []
        self.waits = 0


def _drive(run: SpawnedRun, first: list, *, within: float = 20.0,
           cancels: list[tuple[Callable[[], bool], float]] = ()) -> Driven:
    """The worker loop's part for one run: wait on its descriptor and deadlines until its Done comes;
    ``cancels``: (when, grace) pairs, each acted on once its ``when`` says so."""
    inbox: Inbox = Inbox()
    driven, begun = Driven(), time.monotonic()
    events, pending = list(first), list(cancels)
    try:
        while True:
            driven.started += [e for e in events if isinstance(e, Started)]
            driven.done += [e for e in events if isinstance(e, Done)]
            if driven.done:
                break
            now = time.monotonic()
            assert now - begun < within, "the run never ended"
            while pending and pending[0][0]():
                run.cancel(pending.pop(0)[1])
            due = run.due()                             # as the worker: a tick only when one is due
            events = run.tick(now) if due is not None and due <= now else []
            due = run.due()
            timeout = 0.2 if due is None else max(0.0, min(0.2, due - now))
            inbox.wait(timeout, {run.fileno(): inbox_put(inbox, run)} if run.fileno() >= 0 else {})
            driven.waits += 1
            events += inbox.take()
    finally:
        inbox.close()
    assert len(driven.done) == 1
    return driven


def after(seconds: float) -> Callable[[], bool]:
    begun = time.monotonic()
    return lambda: time.monotonic() - begun >= seconds


def logged(run: SpawnedRun, text: str) -> Callable[[], bool]:
    """True once the job's log holds ``text`` (the job says it is ready for what the test does next)."""
    log = run.output_dir / "log.txt"
    return lambda: log.exists() and text in log.read_text()


def test_a_launched_command_runs_and_is_judged_by_the_loop(store, tmp_path):
    run = _run(store, tmp_path, PASSING[0])
    driven = _drive(run, run.start())
    done = driven.done[0]
    assert [event.pid for event in driven.started] == [run.pid]
    assert done.result.status is JobState.PASSED and done.result.exit_code == 0
    assert "<testcase" in (done.result.junit_xml or "")
    assert run.fileno() == -1                       # its process descriptor is closed once it ended
    with pytest.raises(ChildProcessError):
        os.waitpid(run.pid, os.WNOHANG)             # reaped by the run, no zombie left


def test_a_launched_command_past_its_timeout_gets_sigterm_then_sigkill(store, tmp_path):
    # SIGTERM is ignored: only the SIGKILL after the grace ends it; a grandchild in its group dies too
    run = _run(store, tmp_path, "trap '' TERM; sleep 60 & sleep 60", timeout=0.3, grace=0.3)
    begun = time.monotonic()
    done = _drive(run, run.start()).done[0]
    assert done.result.status is JobState.TIMEOUT and done.result.reason == "timed out after 0.3 s"
    assert time.monotonic() - begun >= 0.55          # the timeout, then the whole grace
    assert living_members(run.pid) == []


def test_a_cancelled_launched_command_gets_sigint_then_its_grace(store, tmp_path):
    run = _run(store, tmp_path, "trap 'echo stopping; exit 3' INT; echo ready; while :; do sleep 0.05; done")
    done = _drive(run, run.start(), cancels=[(logged(run, "ready"), 5.0)]).done[0]
    assert done.result.status is JobState.CANCELLED
    assert "stopping" in (tmp_path / "res" / "j0" / "log.txt").read_text()   # it had its say
    assert living_members(run.pid) == []


def test_a_command_that_cannot_start_ends_with_a_launch_failure(store, tmp_path):
    run = _run(store, tmp_path, "true")
    run.batch = replace(run.batch, command=("no-such-command-here", "{SCENARIO}"))
    events = run.start()
    assert len(events) == 1 and isinstance(events[0], Done)
    assert events[0].result.status is JobState.ERROR
    assert events[0].result.reason.startswith("cannot start the launch command: ")
    assert run.due() is None and run.tick(time.monotonic()) == []


def test_a_cancel_before_the_start_is_kept_and_acted_on_at_once(store, tmp_path):
    run = _run(store, tmp_path, "sleep 60")
    run.cancel(grace=0)                               # before start(): remembered
    begun = time.monotonic()
    done = _drive(run, run.start()).done[0]
    assert done.result.status is JobState.CANCELLED and done.result.reason != NOT_STARTED_REASON
    assert time.monotonic() - begun < 10             # killed at once, not after the sleep


def test_a_timeout_during_a_cancels_grace_is_the_verdict_and_the_loop_does_not_spin(store, tmp_path):
    """As on the thread path, the timeout still comes while a cancel's grace runs (SIGTERM, the verdict a
    timeout); the SIGKILL comes when the earlier of the two graces ends; the loop sleeps meanwhile."""
    run = _run(store, tmp_path, "trap '' INT TERM; echo ready; sleep 60", timeout=1.0, grace=1.5)
    begun = time.monotonic()
    driven = _drive(run, run.start(), cancels=[(logged(run, "ready"), 1.5)])
    assert driven.done[0].result.status is JobState.TIMEOUT
    assert time.monotonic() - begun >= 1.0
    assert driven.waits < 500                       # a wait per deadline or 0.2 s, not a busy loop
    assert living_members(run.pid) == []


def test_a_job_that_ends_at_its_cancel_leaves_its_group_the_grace_then_ends(store, tmp_path):
    """The job ends at SIGINT, a process of its group ignores it: the run ends when the grace is over (the
    loop looks at the group until then), with the group killed."""
    script = "(trap '' INT; echo ready; exec sleep 60) & trap 'exit 4' INT; while :; do sleep 0.05; done"
    run = _run(store, tmp_path, script)
    begun = time.monotonic()
    driven = _drive(run, run.start(), cancels=[(logged(run, "ready"), 1.0)])
    assert driven.done[0].result.status is JobState.CANCELLED
    assert 1.0 <= time.monotonic() - begun < 15
    assert living_members(run.pid) == []


def test_a_forced_stop_cuts_the_groups_grace_short(store, tmp_path):
    """The job ends at SIGINT but leaves a process of its group that ignores it: a second, forced cancel
    (Ctrl-C twice, a lost lease) kills it at once instead of waiting for the first cancel's grace."""
    script = "(trap '' INT; echo ready; exec sleep 60) & trap 'exit 4' INT; while :; do sleep 0.05; done"
    run = _run(store, tmp_path, script)
    begun = time.monotonic()
    ended = lambda: run._ended is not None          # noqa: E731 - the job itself ended, its group did not
    driven = _drive(run, run.start(), cancels=[(logged(run, "ready"), 30.0), (ended, 0.0)])
    assert driven.done[0].result.status is JobState.CANCELLED
    assert time.monotonic() - begun < 20            # not the 30 s grace
    assert living_members(run.pid) == []


# ---------------------------------------------------------------------------- the server's stamps
class _TestServer:
    """What a ForkedRun asks of the fork server; the test gives the replies."""

    mark = "SCENARIO_BATCH_RUNNER=test"

    def submit(self, argv, **_request) -> str:
        return "r1"

    def withdraw(self, request_id: str) -> None:
        pass


def test_a_forked_jobs_times_and_timeout_are_the_servers_stamps_not_when_the_loop_read_them(store, tmp_path):
    """The loop may read the server's replies a while after they were sent (it lets them gather while
    jobs wait at the server): the job's start, end and timeout go by the moments the server stamped."""
    spawned = _run(store, tmp_path, "true", timeout=5.0)
    (tmp_path / "j0.sce").write_text("x")
    run = ForkedRun(spawned.job, replace(spawned.batch, command=()), spawned.output_dir, spawned.scenario_path,
                    _TestServer(), lambda _reply: None, cwd=None, environment={},
                    folder_root=(str(tmp_path / "res"), str(tmp_path / "res")))
    assert run.start() == []
    ended = subprocess.Popen(["true"], start_new_session=True)     # a pid whose group is gone
    ended.wait()
    began = time.monotonic() - 2.0
    [started] = run.on_reply({"id": "r1", "event": "started", "pid": ended.pid, "at": began})
    assert started.at == began and started.began == pytest.approx(time.time() - 2.0, abs=0.5)
    assert run.due() == began + 5.0                              # the timeout counts from the stamped start
    (spawned.output_dir / "test.xml").write_text('<testsuite><testcase name="t"/></testsuite>')
    [done] = run.on_reply({"id": "r1", "event": "exited", "pid": ended.pid, "status": 0, "at": began + 1.5})
    assert isinstance(done, Done) and done.result.status is JobState.PASSED
    assert done.result.started_at == started.began
    assert done.result.finished_at - done.result.started_at == pytest.approx(1.5, abs=0.05)


def test_a_stop_withdraws_the_jobs_waiting_at_the_server_next_to_start_first_then_stops_the_newest(store, tmp_path):
    """Between two withdraws a slot may free: the server then starts the oldest job still waiting. So the
    waiting jobs are taken back oldest first, before any running one is stopped (whose slot would take one)."""
    batch = store.create_batch(mode="local", input_dir=str(tmp_path), output_dir=str(tmp_path / "res"), host="h",
                               command=(), options=BatchOptions(),
                               specs=[JobSpec(f"j{i}", str(tmp_path / f"j{i}.sce"), "0" * 64, "x") for i in range(5)])
    worker = Worker(store, WorkerSettings(slots=2, batch_id=batch.id, watchdog=False), PlainReporter())
    jobs = store.claim(worker.identity, limit=5, batch_id=batch.id)
    runs = [ForkedRun(job, batch, tmp_path / "res" / job.name, job.scenario_path, _TestServer(), lambda _reply: None,
                      cwd=None, environment={}, folder_root=(str(tmp_path), str(tmp_path))) for job in jobs]
    runs[0].pid, runs[1].pid = 101, 102                          # running; j2, j3, j4 wait at the server
    worker._runs = {run.job.id: run for run in runs}
    assert [run.job.name for run in worker._stopping_order()] == ["j2", "j3", "j4", "j1", "j0"]


def test_a_stamp_that_cannot_be_a_past_moment_counts_as_now():
    wall, mono = time.time(), time.monotonic()
    for stamp in (None, "12", True, float("nan"), mono + 30.0, mono - MAX_LAG - 5.0):
        at_wall, at = moment(stamp)
        assert at_wall >= wall and at >= mono, stamp
    at_wall, at = moment(mono - 3.0)
    assert at == mono - 3.0 and at_wall == pytest.approx(wall - 3.0, abs=0.5)
