"""The worker loop: claim jobs, run each in a thread, heartbeat, sweep lost leases, record results.

No SQL here: every database step is a verb of :class:`store.queue.QueueStore`. Only this loop's
thread talks to the store; job threads report through a queue. Results wait in memory until the
store accepts them (backing off while it is unreachable), so a finished result is never dropped
because of a lost connection. The single-host run is this loop scoped to one batch.
"""

from __future__ import annotations

import functools
import gc
import hashlib
import os
import queue
import threading
import time
from collections import Counter, deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO

from executor.batch.builtin_runner import ForkServer, ForkServerError, spare_cores
from executor.batch.job_folders import JobFolders
from executor.batch.job_run import Done, JobRun, Started, StartOrder, job_marker
from executor.batch.progress import Reporter
from executor.batch.repeats import attempt_environment, later_attempts
from executor.batch.verdict import DISK_FULL_REASON, disk_full_result, launch_failure
from executor.batch.watchdog import Watchdog
from executor.process import RUNNER_ENV, disk_full, end_orphan_group, process_alive
from store.database import StoreError
from store.jobs import Batch, Job, JobResult, Reclaimed, WorkerIdentity
from store.queue import DEFAULT_LEASE, DEFAULT_MAX_LOST, LeaseLost, QueueStore, StoreUnavailable
from store.states import RETRYABLE, UNTIL_FAIL_REASON, JobState

if TYPE_CHECKING:
    from store.coverage_records import CoverageRecords

#: Longest wait between two looks at flags (Ctrl-C sets a flag; the loop notices within this time).
_TICK = 0.2

#: After a stop, how long to keep trying to write results to an unreachable store before giving up.
_GIVE_UP_AFTER_STOP = 30.0

#: Seconds a job's child runs before its process id is written to the store. A short job ends sooner:
#: its result is then written alone (one transaction per job instead of two). The record serves to
#: end the child of a runner that died together with its watchdog, which matters for long jobs.
STARTED_RECORD_AFTER = 0.1


@dataclass
class WorkerSettings:
    """How a worker runs: parallel slots, which batches, lease length, where outputs go."""

    slots: int = 1
    batch_id: int | None = None          # only this batch (the single-host run); else any shared batch
    lease: float = DEFAULT_LEASE
    poll: float = 0.5                    # seconds between claims while the queue is empty
    max_lost: int = DEFAULT_MAX_LOST
    output_root: str | None = None       # put job folders here instead of the batch's output folder
    wait_for_work: bool = False          # keep waiting for new batches instead of ending when idle
    echo: BinaryIO | None = None         # copy the children's output here (``-j 1``)
    cwd: str | None = None
    watchdog: bool = True                # every process this worker starts dies with it, even after kill -9
    hand_over_ahead: bool = False        # the single-host run: built-in jobs go to the fork server ahead


@dataclass
class WorkerSummary:
    """What a worker did: verdicts it recorded, whether it was stopped, whether there was any work."""

    verdicts: Counter = field(default_factory=Counter)
    interrupted: bool = False
    nothing_to_do: bool = False
    #: The output folder whose disk filled up (the worker stopped there), else None.
    disk_full: str | None = None


class Worker:
    """Run jobs from the queue until there is no work left (or :meth:`stop` is called)."""

    def __init__(self, store: QueueStore, settings: WorkerSettings, reporter: Reporter,
                 identity: WorkerIdentity | None = None) -> None:
        self.store = store
        self._coverage_records: CoverageRecords | None = None
        self.settings = settings
        self.reporter = reporter
        self.identity = identity or WorkerIdentity.current()
        self.summary = WorkerSummary()
        self._events: queue.Queue = queue.Queue()
        self._runs: dict[int, JobRun] = {}
        self._pending: deque = deque()         # store writes not done yet: Started / Done events
        self._batches: dict[int, Batch] = {}
        self._halted: set[int] = set()
        self._to_halt: set[int] = set()
        self._stop = threading.Event()
        self._force = threading.Event()
        self._cancelling = False
        self._claim_more = True
        self._next_claim = 0.0
        self._backoff = 0.0
        self._retry_at = 0.0
        self._warned_unavailable = False
        self._started = 0
        self._unsure_claims = False
        self._fork_server: ForkServer | None = None
        self._watchdog: Watchdog | None = None        # set while run() runs
        self._ahead: int | None = None                # jobs held ready beyond the slots (see _capacity)
        self._shown_running: set[int] = set()         # jobs the display counts as running
        self._start_order = StartOrder()              # jobs hand their starts over in claim order
        self._folders = JobFolders()
        self._started_due: float | None = None   # when the oldest held start record is to be written

    # ------------------------------------------------------------------ control
    def stop(self, force: bool = False) -> None:
        """Stop claiming and cancel running jobs (safe to call from a signal handler: it only sets flags)."""
        self._stop.set()
        if force:
            self._force.set()

    def run(self) -> WorkerSummary:
        """The loop; returns when no work is left, or after a stop once every running job has ended.

        Should the loop itself fail, the running children are killed before the error propagates (their
        jobs stay ``running`` until the lease expires or ``--resume`` finds this runner gone). Should
        this process die (``kill -9``), its watchdog ends every process it started.
        """
        self._watchdog = Watchdog(self.mark).start() if self.settings.watchdog else None
        gc.collect()
        gc.freeze()      # what exists now (imports, the batch) is not scanned while the loop runs
        try:
            return self._loop()
        except BaseException:
            for run in list(self._runs.values()):
                run.cancel(grace=0)
            for run in list(self._runs.values()):
                run.join(timeout=5.0)
            raise
        finally:
            gc.unfreeze()                        # a later loop in this process freezes afresh
            if self._fork_server is not None:
                self._fork_server.close()
                self._fork_server = None
            if self._watchdog is not None:
                self._watchdog.release()
                self._watchdog = None

    @property
    def mark(self) -> str:
        """``RUNNER_ENV=<worker id>``: the environment entry of every process this worker starts."""
        return f"{RUNNER_ENV}={self.identity.id}"

    def _launcher(self) -> ForkServer:
        """The built-in runner's fork server, started on the first job that needs it (again if it ended)."""
        if self._fork_server is None or not self._fork_server.alive:
            if self._fork_server is not None:
                self._fork_server.close()
                self._fork_server = None
            self._fork_server = ForkServer({**os.environ, RUNNER_ENV: self.identity.id},
                                           keep_spare=spare_cores(self.settings.slots), limit=self.settings.slots,
                                           on_scratch=self._watchdog.remove_on_death if self._watchdog else None,
                                           ).start()
        return self._fork_server

    def _loop(self) -> WorkerSummary:
        beat_every = max(0.05, self.settings.lease / 4)
        next_beat = next_sweep = 0.0
        stopped_at: float | None = None
        while True:
            now = time.monotonic()
            if now >= self._retry_at:
                self._flush()
            if self._stop.is_set():
                self._cancel_all()
                stopped_at = stopped_at or now
                if not self._runs and self._pending and now - stopped_at > _GIVE_UP_AFTER_STOP:
                    self.reporter.warn(f"{len(self._pending)} result(s) could not be written to the store")
                    self._pending.clear()
            if now >= self._retry_at and now >= next_sweep:
                if self._guard(self._sweep):
                    next_sweep = now + beat_every
            if (self._runs or self._unsure_claims) and now >= self._retry_at and \
                    (now >= next_beat or self._unsure_claims):
                if self._guard(self._heartbeat):
                    next_beat = now + beat_every
            if self._may_claim(now):
                self._guard(self._claim)
            if not self._runs and not self._pending:
                if self._stop.is_set():
                    self.summary.interrupted = True
                    break
                if time.monotonic() >= self._retry_at and not self._claim_more:
                    remaining = self._guard(self._remaining)
                    if remaining == 0 and not self.settings.wait_for_work:
                        self.summary.nothing_to_do = self._started == 0
                        break
            self._wait_for_event()
        return self.summary

    # ------------------------------------------------------------------ steps
    def _guard(self, step):
        """Run a store step; while the store is unreachable, back off (0.5 s doubling to 30 s) and say so once."""
        try:
            value = step()
        except StoreUnavailable as exc:
            self._backoff = min(30.0, max(0.5, self._backoff * 2))
            self._retry_at = time.monotonic() + self._backoff
            if not self._warned_unavailable:
                self.reporter.warn(f"{exc}; retrying (results are kept until written)")
                self._warned_unavailable = True
            return None
        if self._backoff:
            self._backoff = 0.0
            self._warned_unavailable = False
        return True if value is None else value

    def _capacity(self) -> int:
        """How many jobs this worker holds at once: its slots, and in a batch of the built-in runner as
        many again, handed to the fork server ahead: it holds each until a slot is free and starts it
        the moment a job ends, so no slot waits while this loop records a result and claims the next
        job (measured, 1,000 trivial jobs at -j 2: 1.36 slots busy on average without). Launched
        commands, a ``worker`` (jobs it holds ahead would wait behind its busy slots while other hosts
        idle), ``--halt-on-failure`` (a job handed ahead would start before the failure is known) and
        ``--post-run`` (the next job would start while the last one's hooks still run) hold no more
        than their slots."""
        if self._ahead is None:
            batch_id = self.settings.batch_id
            if batch_id is None or not self.settings.hand_over_ahead:
                self._ahead = 0
            else:
                batch = self._batch(batch_id)
                options = batch.options
                ahead = not batch.command and not options.halt_on_failure and not options.post_run \
                    and not options.until_fail
                self._ahead = self.settings.slots if ahead else 0
        return self._holding()

    def _holding(self) -> int:
        """The jobs this worker may hold now (its slots until the first claim has decided on more)."""
        return self.settings.slots + (self._ahead or 0)

    def _may_claim(self, now: float) -> bool:
        free = self._holding() - len(self._runs)
        if self._stop.is_set() or free <= 0 or now < self._retry_at:
            return False
        if self.settings.batch_id is not None and self.settings.batch_id in self._halted:
            return False
        return self._claim_more or now >= self._next_claim

    def _claim(self) -> None:
        free = self._capacity() - len(self._runs)
        try:
            jobs = self.store.claim(self.identity, limit=free, batch_id=self.settings.batch_id,
                                    shared_only=self.settings.batch_id is None, lease=self.settings.lease)
        except StoreUnavailable:
            self._unsure_claims = True      # the claim may have committed without us hearing back
            raise
        self._claim_more = len(jobs) == free
        if not self._claim_more:
            self._next_claim = time.monotonic() + self.settings.poll
        for index, job in enumerate(jobs):
            try:
                self._start(job)
            except BaseException:
                self._give_back([j.id for j in jobs[index:]])
                raise

    def _give_back(self, job_ids: list[int]) -> None:
        """Release claimed jobs that will not be started here (if the store is unreachable, the next heartbeat does)."""
        try:
            self.store.release(self.identity, job_ids)
        except StoreUnavailable:
            self._unsure_claims = True

    def _batch(self, batch_id: int) -> Batch:
        if batch_id not in self._batches:
            self._batches[batch_id] = self.store.batch(batch_id)
        return self._batches[batch_id]

    def _start(self, job: Job) -> None:
        """Start a claimed job's thread; a job that cannot be prepared ends with a launch failure.

        Raises only when the store cannot say how to run it (its batch, its scenario text), so the caller
        gives the job back instead.
        """
        batch = self._batch(job.batch_id)
        root = Path(self.settings.output_root or batch.output_dir)
        output_dir = root / job.name
        began = time.time()
        problem: str | None = None
        full_disk = False                   # the problem is a full disk: the job is stopped, not judged
        made_folder = False
        try:
            made_folder = self._folders.prepare(root, output_dir)
            scenario = self._scenario_file(job, batch, output_dir)
        except StoreError:
            raise
        except OSError as exc:
            full_disk = disk_full(exc)
            scenario, problem = job.scenario_path, f"cannot prepare the job: {exc.strerror or exc}" + (
                f": {exc.filename}" if exc.filename else "")
        except Exception as exc:  # noqa: BLE001 - one job that cannot be prepared must not end the loop
            scenario, problem = job.scenario_path, f"cannot prepare the job: {exc!r}"
        launcher = None
        if problem is None and not batch.command:
            try:
                launcher = self._launcher()
            except ForkServerError as exc:
                problem = str(exc)
        run = JobRun(job, batch, output_dir, scenario, self._events, cwd=self.settings.cwd,
                     echo=self.settings.echo if self.settings.slots == 1 else None,
                     environment={RUNNER_ENV: self.identity.id, **attempt_environment(job, batch.options.repeat)},
                     launcher=launcher, made_folder=made_folder,
                     order=(self._start_order, self._start_order.take()))
        self._runs[job.id] = run
        self._started += 1
        if problem is None:
            try:
                run.start()
                return
            except RuntimeError as exc:           # no thread could be started
                problem = f"cannot start the job: {exc}"
        run.pass_turn()                           # it never starts: the next job need not wait for it
        ended = time.time()
        self._events.put(Done(run, disk_full_result(output_dir, began, ended) if full_disk
                              else launch_failure(output_dir, began, ended, problem)))

    def _scenario_file(self, job: Job, batch: Batch, output_dir: Path) -> str:
        """The scenario path to run: the original file, or (on a host without it) the copy kept in the store."""
        path = job.scenario_path
        if batch.mode == "local":
            return path
        try:
            if hashlib.sha256(Path(path).read_bytes()).hexdigest() == job.scenario_sha:
                return path
        except OSError:
            pass
        text = self.store.scenario_text(job.id)
        if text is None:
            return path
        output_dir.mkdir(parents=True, exist_ok=True)
        copy = output_dir / Path(path).name
        copy.write_text(text, encoding="utf-8")
        return str(copy)

    def _heartbeat(self) -> None:
        held = self.store.heartbeat(self.identity, self.settings.lease)
        phantoms = held - set(self._runs)
        if phantoms:                          # claimed, but the reply never reached us: give them back
            self.store.release(self.identity, phantoms)
        self._unsure_claims = False
        for job_id, run in self._runs.items():
            if job_id not in held and not run.lost:
                run.lost = True
                self.reporter.warn(f"lost the lease on {run.job.name}; stopping it, another worker runs it")
                run.cancel(grace=0)

    def _sweep(self) -> None:
        """Take back jobs of dead holders on this host at once, and of any holder whose lease expired."""
        reclaimed: list[Reclaimed] = []
        dead = {j.worker_id for j in self.store.running(self.settings.batch_id,
                                                        shared_only=self.settings.batch_id is None)
                if self.identity.same_node(j.worker_id) and j.worker_id != self.identity.id
                and not process_alive(j.worker_pid)}
        for worker_id in sorted(w for w in dead if w):
            reclaimed += self.store.reclaim_worker(worker_id, "the runner holding it ended without a result",
                                                   max_lost=self.settings.max_lost)
        reclaimed += self.store.reclaim_expired(self.settings.max_lost)
        for item in reclaimed:
            if item.child_pid and self.identity.same_node(item.worker_id) and item.worker_id != self.identity.id:
                # the orphaned child of a dead runner must not run on (if that group is still it)
                end_orphan_group(item.child_pid, job_marker(item.job_id, item.attempt), item.worker_id)
        if reclaimed:
            self._claim_more = True

    def _remaining(self) -> int:
        counts = self.store.counts(self.settings.batch_id, shared_only=self.settings.batch_id is None)
        return counts[JobState.QUEUED] + counts[JobState.RUNNING]

    def _cancel_all(self) -> None:
        # newest first: the jobs handed to the fork server ahead are withdrawn before the running
        # ones are stopped, so none of them starts in the slot a stopped job leaves
        if self._force.is_set():
            for run in reversed(list(self._runs.values())):
                run.cancel(grace=0)
        elif not self._cancelling:
            self._cancelling = True
            for run in reversed(list(self._runs.values())):
                run.cancel()

    # ------------------------------------------------------------------ events and writes
    def _wait_for_event(self) -> None:
        timeout = _TICK
        if self._claim_more and not self._stop.is_set() and len(self._runs) < self._holding() \
                and time.monotonic() >= self._retry_at:
            timeout = 0.0
        if self._started_due is not None:         # wake when a held start record is due (and may be written)
            due = max(self._started_due, self._retry_at)
            timeout = max(0.0, min(timeout, due - time.monotonic()))
        try:
            event = self._events.get(timeout=timeout) if timeout else self._events.get_nowait()
        except queue.Empty:
            return
        self._add(event)
        while True:
            try:
                self._add(self._events.get_nowait())
            except queue.Empty:
                break

    def _add(self, event: Started | Done) -> None:
        """Queue a store write; a job's result makes the not yet written record of its start pointless.

        The display counts a job as running from its start (a job handed to the fork server ahead
        waits for a slot), or from its result when it never started."""
        if isinstance(event, Started) or event.run.job.id not in self._shown_running:
            self._shown_running.add(event.run.job.id)
            self.reporter.job_started(event.run.job)
        if isinstance(event, Done) and any(isinstance(e, Started) and e.run is event.run for e in self._pending):
            self._pending = deque(e for e in self._pending if not (isinstance(e, Started) and e.run is event.run))
        self._pending.append(event)

    def _flush(self) -> None:
        held: list[Started] = []                # starts too recent to record yet (see STARTED_RECORD_AFTER)
        now = time.monotonic()
        try:
            while self._pending:
                event = self._pending[0]
                if isinstance(event, Started) and now - event.at < STARTED_RECORD_AFTER \
                        and not self._stop.is_set():
                    held.append(self._pending.popleft())
                    continue
                if self._guard(functools.partial(self._write, event)) is None:
                    return
                self._pending.popleft()
        finally:
            self._pending.extendleft(reversed(held))
            self._started_due = min(e.at for e in held) + STARTED_RECORD_AFTER if held else None
        while self._to_halt:
            batch_id = min(self._to_halt)
            if self._guard(functools.partial(self._halt, batch_id)) is None:
                return
            self._to_halt.discard(batch_id)

    def _write(self, event: Started | Done) -> None:
        run = event.run
        if isinstance(event, Started):
            if not run.lost:
                self.store.started(run.job, event.pid)
            return
        for problem in event.problems:
            self.reporter.warn(f"{run.job.name}: {problem}")
        event.problems = []                    # said once, even if the write below has to be repeated
        if run.lost:
            self._runs.pop(run.job.id, None)
            return
        result, job = event.result, run.job
        retrying = False
        if result.reason == DISK_FULL_REASON and self.summary.disk_full is None:
            self.summary.disk_full = str(run.output_dir.parent)
            self.reporter.warn(f"no space left on the device holding {run.output_dir.parent}: stopping (the jobs "
                               "under way are stopped; make room, then finish with --resume)")
            self.stop()
        try:
            if result.status is JobState.CANCELLED:
                self.store.cancel(job, result)
            elif (result.status in RETRYABLE and job.retried < run.batch.options.retries
                  and not self._stop.is_set()):
                self.store.retry(job, result)
                retrying = self._claim_more = True
            else:
                self.store.finish(job, result)
                self._record_coverage(job, result)
                self.summary.verdicts[result.status] += 1
                if result.status is not JobState.PASSED and run.batch.options.halt_on_failure:
                    self._to_halt.add(run.batch.id)
                if result.status is not JobState.PASSED and run.batch.options.until_fail:
                    self.store.halt_jobs(run.batch.id, later_attempts(job.name, run.batch.options.repeat),
                                         UNTIL_FAIL_REASON)
        except LeaseLost as exc:
            self.reporter.warn(f"result of {job.name} refused: {exc}")
            self._runs.pop(job.id, None)
            return
        self._runs.pop(job.id, None)           # the slot frees only once the result is in the store
        self._shown_running.discard(job.id)
        self.reporter.job_finished(job, result, retrying=retrying)

    def _record_coverage(self, job: Job, result: JobResult) -> None:
        """Keep the job's ``coverage.json`` (read on this host with its result) in the store, for reports
        from any host; a file that does not validate is said and left out (the job's verdict stands)."""
        if not result.coverage_json:
            return
        from coverage_engine.coverage.errors import RunFileError
        from coverage_engine.coverage.run_file import parse_run_coverage, run_coverage_dict
        from store.coverage_records import CoverageRecords

        try:
            if self._coverage_records is None:
                self._coverage_records = CoverageRecords.attach(self.store.engine)
            run = parse_run_coverage(result.coverage_json)
            self._coverage_records.record(job.id, job.attempts, run_coverage_dict(run))
        except RunFileError as exc:
            self.reporter.warn(f"{job.name}: coverage.json not kept: {exc.render()}")

    def _halt(self, batch_id: int) -> None:
        if batch_id not in self._halted:
            count = self.store.halt(batch_id)
            self._halted.add(batch_id)
            self._claim_more = False
            if count:
                self.reporter.warn(f"halting: {count} job(s) not started (--halt-on-failure)")
