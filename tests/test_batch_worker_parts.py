"""The worker's parts, each alone, on real stores: claim pacing and back-off, result recording, leases, hand-over."""

from __future__ import annotations

import io
import queue
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from executor.batch.claim_pacing import FIRST_BACKOFF, ClaimPacer, StoreBackoff
from executor.batch.hand_over import AHEAD_PER_SLOT, CLAIM_CHUNK, LINGER, REPLY_ROOM, HandOver
from executor.batch.job_run import Done, JobRun, Started
from executor.batch.leases import LeaseKeeper
from executor.batch.progress import PlainReporter
from executor.batch.recorder import (
    RECORD_AFTER,
    STARTED_RECORD_AFTER,
    RecorderHooks,
    ResultRecorder,
    WorkerSummary,
)
from store.database import open_engine
from store.jobs import Batch, BatchOptions, Job, JobResult, JobSpec, WorkerIdentity
from store.queue import QueueStore
from store.states import JobState

pytest_plugins = ["batch_stores"]            # the store_url and pg_url fixtures


@pytest.fixture
def store(tmp_path: Path) -> Iterator[QueueStore]:
    """A queue in a fresh SQLite file."""
    opened = QueueStore.open(f"sqlite:///{tmp_path / 'store.db'}")
    yield opened
    opened.close()


@pytest.fixture
def any_store(store_url: str) -> Iterator[QueueStore]:
    """A queue in a fresh SQLite file, then in a fresh PostgreSQL database."""
    opened = QueueStore.open(store_url)
    yield opened
    opened.close()


class Clock:
    """A clock the test moves by hand (the parts take ``time.monotonic`` as a parameter)."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def _batch(store: QueueStore, count: int, *, command: tuple[str, ...] = ("run",), retries: int = 0,
           halt: bool = False) -> Batch:
    return store.create_batch(mode="local", input_dir="/in", output_dir="/out", host="h", command=command,
                              options=BatchOptions(retries=retries, halt_on_failure=halt),
                              specs=[JobSpec(f"j{i}", f"/in/j{i}.sce", "0" * 64, "x") for i in range(count)])


def _done(job: Job, batch: Batch, status: JobState = JobState.PASSED) -> Done:
    run = JobRun(job, batch, Path("/out") / job.name, job.scenario_path, queue.Queue())
    now = time.time()
    return Done(run, JobResult(status, 0 if status is JobState.PASSED else 1, now - 0.01, now,
                               junit_xml="<testsuite/>", log_tail=""))


class Recorded:
    """A recorder on a real store, with what it told the worker and printed."""

    def __init__(self, store: QueueStore, *, at_once: bool = False) -> None:
        self.lines, self.warnings = io.StringIO(), []
        self.requeued = self.stopped = 0
        self.halted: list[int] = []
        reporter = PlainReporter(self.lines)
        reporter.warn = self.warnings.append  # type: ignore[method-assign]
        self.summary = WorkerSummary()
        self.recorder = ResultRecorder(store, reporter, StoreBackoff(self.warnings.append), RecorderHooks(
            stop=self._stop, requeued=self._requeued, halted=self.halted.append, stopping=lambda: False),
            self.summary, at_once=at_once)

    def _stop(self) -> None:
        self.stopped += 1

    def _requeued(self) -> None:
        self.requeued += 1


# ---------------------------------------------------------------------------- claim pacing and back-off
def test_backoff_holds_store_steps_back_doubling_and_says_so_once(tmp_path):
    clock = Clock()
    warnings: list[str] = []
    backoff = StoreBackoff(warnings.append, clock)
    away = QueueStore(open_engine("postgresql+psycopg://postgres@127.0.0.1:1/none"))   # nothing listens there
    me = WorkerIdentity.current()
    assert backoff.run(lambda: away.heartbeat(me)) == (False, None)
    assert backoff.retry_at == clock.now + FIRST_BACKOFF and not backoff.ready(clock.now)
    clock.now = backoff.retry_at
    assert backoff.run(lambda: away.heartbeat(me)) == (False, None)
    assert backoff.retry_at == clock.now + 2 * FIRST_BACKOFF
    assert len(warnings) == 1 and "unavailable" in warnings[0] and "results are kept" in warnings[0]
    here = QueueStore.open(f"sqlite:///{tmp_path / 'store.db'}")
    try:
        assert backoff.run(lambda: here.heartbeat(me)) == (True, set())
        clock.now = backoff.retry_at + 1
        assert backoff.run(lambda: away.heartbeat(me))[0] is False
        assert backoff.retry_at == clock.now + FIRST_BACKOFF and len(warnings) == 2   # a new outage, said again
    finally:
        here.close()
        away.close()


def test_claims_go_on_at_once_while_they_fill_the_slots_and_poll_once_the_queue_is_empty():
    clock = Clock()
    pacer = ClaimPacer(0.5, clock)
    assert pacer.due(clock.now)
    pacer.claimed(asked=2, got=2)
    assert pacer.eager and pacer.due(clock.now)
    pacer.claimed(asked=2, got=1)
    assert not pacer.eager and not pacer.due(clock.now + 0.49) and pacer.due(clock.now + 0.5)
    pacer.wake()
    assert pacer.due(clock.now)
    pacer.idle()
    assert not pacer.due(clock.now)


# ---------------------------------------------------------------------------- result recording
def test_results_wait_a_moment_then_are_written_together(any_store):
    batch = _batch(any_store, 3)
    jobs = any_store.claim(WorkerIdentity.current(), limit=3, batch_id=batch.id)
    parts = Recorded(any_store)
    start = time.monotonic()
    for job in jobs:
        parts.recorder.add(_done(job, batch, JobState.PASSED if job.name != "j1" else JobState.FAILED), start)
    assert parts.recorder.due() == pytest.approx(start + RECORD_AFTER)
    assert set(parts.recorder.unwritten()) == {j.id for j in jobs}
    parts.recorder.flush(start)                          # not due yet: nothing written
    assert any_store.counts(batch.id)[JobState.RUNNING] == 3
    parts.recorder.flush(start + RECORD_AFTER)
    counts = any_store.counts(batch.id)
    assert (counts[JobState.PASSED], counts[JobState.FAILED], counts[JobState.RUNNING]) == (2, 1, 0)
    assert not parts.recorder and parts.recorder.due() is None
    assert parts.summary.verdicts == {JobState.PASSED: 2, JobState.FAILED: 1}
    assert parts.lines.getvalue().splitlines()[0].startswith("[1] passed    j0")
    assert [a["outcome"] for a in any_store.attempts(jobs[1].id)] == ["failed"]


def test_a_refused_result_is_said_and_the_others_are_recorded(store):
    batch = _batch(store, 2)
    me = WorkerIdentity.current()
    first, second = store.claim(me, limit=2, batch_id=batch.id)
    store.reclaim_expired(now=time.time() + 3600)          # both leases expired, taken back
    again = store.claim(me, limit=1, batch_id=batch.id)[0]
    assert again.id == first.id
    parts = Recorded(store)
    parts.recorder.add(_done(first, batch), 0.0)            # the first attempt's late result
    parts.recorder.add(_done(again, batch), 0.0)
    parts.recorder.add(_done(second, batch), 0.0)
    parts.recorder.flush(time.monotonic(), force=True)
    assert store.jobs(batch.id)[0].status is JobState.PASSED
    assert store.jobs(batch.id)[1].status is JobState.QUEUED
    assert sum("refused" in w for w in parts.warnings) == 2, parts.warnings


def test_a_retry_queues_the_job_again_and_wakes_the_claims_and_a_failure_halts_its_batch(store):
    retried = _batch(store, 1, retries=1)
    halting = _batch(store, 3, halt=True)
    me = WorkerIdentity.current()
    [job] = store.claim(me, batch_id=retried.id)
    parts = Recorded(store)
    parts.recorder.add(_done(job, retried, JobState.ERROR), time.monotonic())
    parts.recorder.flush(time.monotonic() + RECORD_AFTER)
    assert store.jobs(retried.id)[0].status is JobState.QUEUED and parts.requeued == 1
    assert parts.lines.getvalue().split()[0] == "retry"
    [failing] = store.claim(me, batch_id=halting.id)
    now = time.monotonic()
    parts.recorder.add(_done(failing, halting, JobState.FAILED), now)
    assert parts.recorder.due() == now                     # a batch that halts on failure is written at once
    parts.recorder.flush(now)
    counts = store.counts(halting.id)
    assert (counts[JobState.FAILED], counts[JobState.CANCELLED]) == (1, 2)
    assert parts.halted == [halting.id] and parts.recorder.halted(halting.id)
    assert any("halting: 2 job(s)" in w for w in parts.warnings)


def test_a_job_given_back_to_a_batch_halted_meanwhile_is_cancelled_and_a_resumed_batch_halts_again(store):
    """A job held unstarted while its batch halted (waiting at a fork server that ended, say) goes back
    after the halt: it is cancelled with the rest, not left queued where nothing claims. A batch claimed
    from again after a halt was resumed: it can halt again."""
    halting = _batch(store, 4, halt=True)
    me = WorkerIdentity.current()
    failing, held = store.claim(me, limit=2, batch_id=halting.id)
    parts = Recorded(store)
    parts.recorder.add(_done(failing, halting, JobState.FAILED), time.monotonic())
    parts.recorder.flush(time.monotonic())
    assert parts.recorder.halted(halting.id) and store.counts(halting.id)[JobState.CANCELLED] == 2
    assert store.release(me, [held.id], halted=[held.id]) == 1
    counts = store.counts(halting.id)
    assert (counts[JobState.FAILED], counts[JobState.CANCELLED], counts[JobState.QUEUED]) == (1, 3, 0)
    assert store.resume(halting.id) == 3
    again = store.claim(me, limit=2, batch_id=halting.id)
    parts.recorder.claimed_from({job.batch_id for job in again})
    assert not parts.recorder.halted(halting.id)
    parts.recorder.add(_done(again[0], halting, JobState.FAILED), time.monotonic())
    parts.recorder.flush(time.monotonic())
    assert parts.halted == [halting.id, halting.id] and store.counts(halting.id)[JobState.CANCELLED] == 1


def test_a_start_is_recorded_only_for_a_job_still_running_after_a_while(store):
    batch = _batch(store, 2)
    short, long_ = store.claim(WorkerIdentity.current(), limit=2, batch_id=batch.id)
    parts = Recorded(store, at_once=True)
    now = time.monotonic()
    for job, pid in ((short, 111), (long_, 222)):
        parts.recorder.add(Started(_done(job, batch).run, pid, now), now)
    parts.recorder.add(_done(short, batch), now)           # ended first: its start is never written
    parts.recorder.flush(now)                              # -j 1: a result is written at once
    assert store.jobs(batch.id)[0].status is JobState.PASSED
    assert parts.recorder.due() == pytest.approx(now + STARTED_RECORD_AFTER)
    parts.recorder.flush(now + STARTED_RECORD_AFTER)
    assert [j.child_pid for j in store.jobs(batch.id)] == [None, 222]


# ---------------------------------------------------------------------------- leases
def test_heartbeat_gives_back_unknown_claims_and_names_the_lost_ones(any_store):
    batch = _batch(any_store, 3)
    me = WorkerIdentity.current()
    keeper = LeaseKeeper(any_store, me, lease=60.0, max_lost=3, batch_id=batch.id)
    a, b, c = any_store.claim(me, limit=3, batch_id=batch.id)
    any_store.release(me, [c.id])                              # c is no longer ours
    lost = keeper.heartbeat({a.id, c.id})                  # b: claimed, but its reply never came
    assert lost == {c.id}
    assert [j.status for j in any_store.jobs(batch.id)] == [JobState.RUNNING, JobState.QUEUED, JobState.QUEUED]


def test_sweep_takes_back_the_jobs_of_a_dead_runner_on_this_host_at_once(store):
    batch = _batch(store, 2)
    me = WorkerIdentity.current()
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    host, _pid, node, _nonce = me.id.split(":")
    dead = WorkerIdentity(id=f"{host}:{gone.pid}:{node}:deadbeef", host=host, pid=gone.pid, node=node)
    store.claim(dead, limit=1, batch_id=batch.id)
    keeper = LeaseKeeper(store, me, lease=60.0, max_lost=3, batch_id=batch.id)
    [taken] = keeper.sweep()
    assert taken.worker_id == dead.id and taken.status is JobState.QUEUED
    assert store.counts(batch.id)[JobState.QUEUED] == 2
    assert keeper.sweep() == []


# ---------------------------------------------------------------------------- hand-over
def test_hand_over_holds_jobs_ahead_only_for_a_built_in_batch_of_the_single_host_run(store):
    built_in, launched = _batch(store, 1, command=()), _batch(store, 1)
    halting = _batch(store, 1, command=(), halt=True)
    assert AHEAD_PER_SLOT > 1
    assert HandOver("w", 2, ahead_allowed=True).decide(built_in) == 2 + 2 * AHEAD_PER_SLOT
    assert HandOver("w", 1, ahead_allowed=True, threaded=True).decide(built_in) == 2   # a thread waits per job
    assert HandOver("w", 2, ahead_allowed=True).decide(launched) == 2
    assert HandOver("w", 2, ahead_allowed=True).decide(halting) == 2
    assert HandOver("w", 2, ahead_allowed=False).decide(built_in) == 2
    undecided = HandOver("w", 3, ahead_allowed=True)
    assert undecided.holding() == 3


def test_hand_over_claims_a_chunk_only_in_a_single_host_batch_that_cannot_halt(store):
    built_in, launched = _batch(store, 1, command=()), _batch(store, 1)
    halting = _batch(store, 1, halt=True)

    def limit(hand_over: HandOver, batch: Batch, free: int) -> int:
        hand_over.decide(batch)
        return hand_over.claim_limit(free)

    assert limit(HandOver("w", 2, ahead_allowed=True), built_in, 1) == max(CLAIM_CHUNK, 2 + 2 * AHEAD_PER_SLOT)
    assert limit(HandOver("w", 2, ahead_allowed=True), launched, 2) == CLAIM_CHUNK
    assert limit(HandOver("w", 40, ahead_allowed=True), built_in, 3) == 40 * (1 + AHEAD_PER_SLOT)   # all it holds
    assert limit(HandOver("w", 2, ahead_allowed=True), halting, 1) == 1          # never past a failure
    assert limit(HandOver("w", 2, ahead_allowed=False), built_in, 2) == 2        # a worker leaves the rest
    assert HandOver("w", 2, ahead_allowed=True).claim_limit(2) == 2              # undecided: what is free


def test_the_loop_lingers_only_while_the_jobs_waiting_at_the_server_keep_every_slot_busy(store):
    """Replies may gather while the jobs held at the server would keep its slots busy for twice as long, at
    the rate jobs started lately; never longer than LINGER, and not at all without jobs handed ahead."""
    built_in, halting = _batch(store, 1, command=()), _batch(store, 1, command=(), halt=True)
    ahead = HandOver("w", 2, ahead_allowed=True)
    ahead.decide(built_in)
    assert ahead.linger(16, 10.0) == 0.0                     # no start seen yet: no rate
    for i in range(11):
        ahead.started(10.0 + i * 0.01)                       # 100 starts a second
    assert ahead.linger(16, 10.1) == LINGER                  # 16 waiting: 160 ms of work, more than enough
    assert ahead.linger(4, 10.1) == pytest.approx(4 / (11 / 0.1) / 2)    # 4 of 110 a second: half their time
    assert ahead.linger(1, 10.1) == 0.0                      # fewer than the slots: every reply counts
    for i in range(40):
        ahead.started(20.0 + i * 0.001)                      # 1,000 a second: only the latest starts count
    assert ahead.linger(16, 20.04) == pytest.approx(16 / (32 / (20.04 - 20.008)) / 2)
    many = HandOver("w", 64, ahead_allowed=True)
    many.decide(built_in)
    for i in range(32):
        many.started(30.0 + i / 5000)                        # 5,000 a second: the socket would fill first
    rate = 32 / (30.0064 - 30.0)
    assert REPLY_ROOM / 2 / rate < LINGER and many.linger(512, 30.0064) == pytest.approx(REPLY_ROOM / 2 / rate)
    held_back = HandOver("w", 2, ahead_allowed=True)
    held_back.decide(halting)
    for i in range(11):
        held_back.started(10.0 + i * 0.01)
    assert held_back.linger(16, 10.1) == 0.0                 # nothing handed ahead: read every reply at once


def test_hand_over_starts_one_fork_server_and_again_after_it_ended(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))     # where the server's scratch folder goes
    scratch: list[str] = []
    hand_over = HandOver("test-runner", 1, ahead_allowed=False, on_scratch=scratch.append)
    try:
        server = hand_over.launcher()
        assert server.alive and hand_over.launcher() is server
        assert server.environment["SCENARIO_BATCH_RUNNER"] == "test-runner"
        assert scratch and Path(scratch[0]).parent == tmp_path
        server.close()
        assert hand_over.launcher() is not server and len(scratch) == 2
    finally:
        hand_over.close()
    assert list(tmp_path.iterdir()) == []                    # the scratch folders went with their servers
