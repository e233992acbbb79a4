"""The worker: a loop that claims jobs, starts each in a thread, and hands its events to the parts.

No SQL here and no policy of its own: each part has one job and is tested alone.

* :mod:`executor.batch.claim_pacing`: when to claim (at once, or after the poll interval) and the
  back-off while the store is unreachable;
* :mod:`executor.batch.hand_over`: the built-in runner's fork server and how many jobs to hold;
* :mod:`executor.batch.recorder`: the store writes of starts and results, several per transaction;
* :mod:`executor.batch.leases`: heartbeats, and taking back the jobs of dead or silent holders;
* :mod:`executor.batch.watchdog`: every process this worker starts dies with it, even after ``kill -9``.

Only this loop's thread talks to the store; job threads report through its inbox (:mod:`executor.batch.inbox`). A job's slot frees
when the job ends; its result waits in the recorder until the store accepts it (backing off while
the store is unreachable), so a finished result is never dropped because of a lost connection. The
single-host run is this loop scoped to one batch.
"""

from __future__ import annotations

import functools
import gc
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from executor.batch.builtin_runner import ForkServer
from executor.batch.claim_pacing import ClaimPacer, StoreBackoff
from executor.batch.fork_errors import ForkServerError
from executor.batch.forked_run import ForkedRun, Reply
from executor.batch.hand_over import HandOver
from executor.batch.inbox import Inbox
from executor.batch.job_folders import JobFolders, scenario_to_run
from executor.batch.job_run import Done, JobRun, Started
from executor.batch.leases import LeaseKeeper
from executor.batch.loop_run import LoopRun
from executor.batch.progress import Reporter
from executor.batch.recorder import STARTED_RECORD_AFTER, RecorderHooks, ResultRecorder, WorkerSummary
from executor.batch.repeats import attempt_environment
from executor.batch.spawned_run import SpawnedRun, loop_can_spawn
from executor.batch.verdict import disk_full_result, launch_failure, never_started
from executor.batch.watchdog import Watchdog
from executor.children.process import RUNNER_ENV, disk_full
from executor.children.spawn import can_spawn_logged
from store.database import StoreError
from store.jobs import Batch, Job, WorkerIdentity
from store.queue import DEFAULT_LEASE, DEFAULT_MAX_LOST, QueueStore, StoreUnavailable
from store.states import JobState

__all__ = ["STARTED_RECORD_AFTER", "Worker", "WorkerSettings", "WorkerSummary"]

#: Longest wait between two looks at flags (Ctrl-C sets a flag; the loop notices within this time).
_TICK = 0.2

#: After a stop, how long to keep trying to write results to an unreachable store before giving up.
_GIVE_UP_AFTER_STOP = 30.0


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
    forkers: int | None = None           # processes forking built-in jobs (None: as the slots and cores call for)


class Worker:
    """Run jobs from the queue until there is no work left (or :meth:`stop` is called)."""

    def __init__(self, store: QueueStore, settings: WorkerSettings, reporter: Reporter,
                 identity: WorkerIdentity | None = None, early: ForkServer | None = None) -> None:
        """``early``: a fork server launched for this worker (``identity``) before the batch was known."""
        self.store = store
        self.settings = settings
        self.reporter = reporter
        self.identity = identity or WorkerIdentity.current()
        self.summary = WorkerSummary()
        self.backoff = StoreBackoff(reporter.warn)
        self.pacer = ClaimPacer(settings.poll)
        self.leases = LeaseKeeper(store, self.identity, lease=settings.lease, max_lost=settings.max_lost,
                                  batch_id=settings.batch_id)
        self.hand_over = HandOver(self.identity.id, settings.slots, ahead_allowed=settings.hand_over_ahead
                                  and settings.batch_id is not None, forkers=settings.forkers, early=early,
                                  threaded=settings.slots == 1 and settings.echo is not None)
        self.recorder = ResultRecorder(store, reporter, self.backoff, RecorderHooks(
            stop=self.stop, requeued=self.pacer.wake, halted=lambda _batch: self.pacer.idle(),
            stopping=self._stop_is_set), self.summary,
            # -j 1, and a worker of a shared queue (other hosts act on its records): each result at once
            at_once=settings.slots == 1 or not settings.hand_over_ahead)
        self._events: Inbox[Started | Done | Reply] = Inbox()
        self._runs: dict[int, JobRun | LoopRun] = {}   # jobs started and not ended
        self._driven: dict[int, LoopRun] = {}          # those of them the loop drives (see loop_run)
        self._can_spawn: bool | None = None            # launched commands may be SpawnedRuns (decided once)
        self._waiting: deque[Job] = deque()            # jobs claimed in a chunk, not started yet
        self._batches: dict[int, Batch] = {}
        self._stop = threading.Event()
        self._force = threading.Event()
        self._cancelling = False
        self._started = 0
        self._unsure_claims = False                    # a claim may have committed unheard: heartbeat soon
        self._shown_running: set[int] = set()          # jobs the display counts as running
        self._taken_back: dict[int, int] = {}          # jobs taken back before their start (id: batch id), to give back
        self._folders = JobFolders()

    # ------------------------------------------------------------------ control
    def stop(self, force: bool = False) -> None:
        """Stop claiming and cancel running jobs (safe to call from a signal handler: it only sets flags)."""
        self._stop.set()
        if force:
            self._force.set()

    def _stop_is_set(self) -> bool:
        return self._stop.is_set()

    def run(self) -> WorkerSummary:
        """The loop; returns when no work is left, or after a stop once every running job has ended.

        Should the loop itself fail, the running children are killed before the error propagates (their
        jobs stay ``running`` until the lease expires or ``--resume`` finds this runner gone). Should
        this process die (``kill -9``), its watchdog ends every process it started.
        """
        watchdog = Watchdog(self.mark).start() if self.settings.watchdog else None
        self.hand_over.on_scratch = watchdog.remove_on_death if watchdog else None
        gc.collect()
        gc.freeze()      # what exists now (imports, the batch) is not scanned while the loop runs
        try:
            return self._loop()
        except BaseException:
            for run in list(self._runs.values()):
                run.cancel(grace=0)
            self._let_threads_end(5.0)
            raise
        finally:
            gc.unfreeze()                        # a later loop in this process freezes afresh
            self.hand_over.close()
            if not any(run.alive() for run in self._runs.values()):
                self._events.close()             # (a thread still running may yet write to it)
            if watchdog is not None:
                watchdog.release()

    def _let_threads_end(self, seconds: float) -> None:
        """After a failure of the loop (every job was sent SIGKILL): reap the children the loop watched,
        and give the job threads up to ``seconds`` to end, reading the fork server's replies meanwhile
        (a thread of a built-in job may wait for them); the events that come are dropped."""
        for driven in list(self._driven.values()):
            driven.abandon()
        end = time.monotonic() + seconds
        for run in list(self._runs.values()):
            while run.alive() and time.monotonic() < end:
                if self.hand_over.server is None:
                    run.join(0.05)
                else:
                    self._events.wait(0.05, self._watched())
                    self._events.take()

    @property
    def mark(self) -> str:
        """``RUNNER_ENV=<worker id>``: the environment entry of every process this worker starts."""
        return f"{RUNNER_ENV}={self.identity.id}"

    def _loop(self) -> WorkerSummary:
        next_beat = next_sweep = 0.0
        stopped_at: float | None = None
        while True:
            now = time.monotonic()
            self._tick_driven(now)
            ready = self.backoff.ready(now)
            if ready:
                self.recorder.flush(now, force=self._stop.is_set())
            if self._stop.is_set():
                self._cancel_all()
                stopped_at = stopped_at or now
                if not self._runs and now - stopped_at > _GIVE_UP_AFTER_STOP:
                    self._give_up_writes()
            if ready and now >= next_sweep and self._store_step(self._sweep):
                next_sweep = now + self.leases.every
            if ready and (self._runs or self._waiting or self.recorder or self._unsure_claims) \
                    and (now >= next_beat or self._unsure_claims) and self._store_step(self._heartbeat):
                next_beat = now + self.leases.every
            if self._taken_back and ready:
                self._store_step(self._give_back_taken)
            if self._waiting and ready and not self._stop.is_set():
                self._store_step(self._start_waiting)
            if self._may_claim(now):
                self._store_step(self._claim)
            if not self._runs and not self._waiting and not self.recorder and not self._taken_back:
                if self._stop.is_set():
                    self.summary.interrupted = True
                    break
                if self.backoff.ready(time.monotonic()) and not self.pacer.eager:
                    ok, remaining = self.backoff.run(self._remaining)
                    if ok and remaining == 0 and not self.settings.wait_for_work:
                        self.summary.nothing_to_do = self._started == 0
                        break
            self._wait_for_event()
        return self.summary

    def _give_up_writes(self) -> None:
        """After a stop the store stayed away: drop what could not be written (``--resume`` runs those jobs)."""
        if self.recorder:
            self.reporter.warn(f"{self.recorder.drop()} result(s) could not be written to the store")
        if self._taken_back:
            self.reporter.warn(f"{len(self._taken_back)} job(s) not started could not be given back to the queue")
            self._taken_back.clear()

    def _give_back_taken(self) -> None:
        """Give the jobs taken back before their start back to the queue, all in one store statement,
        under the back-off: a stop's (claimed and not handed over, or withdrawn from the fork server) and
        those a fork server ended before forking them. Those of a batch this worker halted meanwhile are
        cancelled as its halt cancelled the rest (nothing claims from it any more)."""
        halted = [job_id for job_id, batch_id in self._taken_back.items() if self.recorder.halted(batch_id)]
        self.store.release(self.identity, self._taken_back, halted=halted)
        self._taken_back.clear()
        self.pacer.wake()                 # (those of a fork server that ended run on the next one at once)

    def _store_step(self, step: Callable[[], None]) -> bool:
        """Run a store step under the back-off; whether the store took it."""
        return self.backoff.run(step)[0]

    # ------------------------------------------------------------------ claiming and starting
    def _may_claim(self, now: float) -> bool:
        free = self.hand_over.holding() - len(self._runs)
        if self._stop.is_set() or self._waiting or free <= 0 or not self.backoff.ready(now):
            return False
        if self.settings.batch_id is not None and self.recorder.halted(self.settings.batch_id):
            return False
        return self.pacer.due(now)

    def _claim(self) -> None:
        holding = self.hand_over.holding() if self.settings.batch_id is None else \
            self.hand_over.decide(self._batch(self.settings.batch_id))
        limit = self.hand_over.claim_limit(holding - len(self._runs))
        try:
            jobs = self.store.claim(self.identity, limit=limit, batch_id=self.settings.batch_id,
                                    shared_only=self.settings.batch_id is None, lease=self.settings.lease)
        except StoreUnavailable:
            self._unsure_claims = True      # the claim may have committed without us hearing back
            raise
        self.pacer.claimed(limit, len(jobs))
        self.recorder.claimed_from({job.batch_id for job in jobs})
        self._waiting.extend(jobs)
        self._start_waiting()

    def _start_waiting(self) -> None:
        """Start claimed jobs while a slot is free (claim order); one the store could not prepare waits on.
        The fork server hears of the built-in ones at the end, all in one message."""
        try:
            while self._waiting and len(self._runs) < self.hand_over.holding():
                job = self._waiting.popleft()
                try:
                    self._start(job)
                except BaseException:
                    self._waiting.appendleft(job)
                    raise
        finally:
            self.hand_over.send_submitted()

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
        echo = self.settings.echo if self.settings.slots == 1 else None
        # a built-in job's folder is made by the fork server as the job starts (not by this process)
        folder_root = None
        try:
            if batch.command or echo is not None:
                made_folder = self._folders.prepare(root, output_dir)
            else:
                folder_root = (str(root), self._folders.real_root(root))
            scenario = scenario_to_run(self.store, job, batch, output_dir)
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
                launcher = self.hand_over.launcher()
            except ForkServerError as exc:
                problem = str(exc)
        run = self._new_run(job, batch, output_dir, scenario, launcher,
                            folder_root, made_folder, startable=problem is None)
        self._runs[job.id] = run
        self._started += 1
        if problem is None:
            try:
                if isinstance(run, LoopRun):
                    for event in run.start():
                        self._events.put(event)
                else:
                    run.start()
                return
            except RuntimeError as exc:           # no thread could be started
                problem = f"cannot start the job: {exc}"
        run.pass_turn()                           # it never starts: the next job need not wait for it
        self._driven.pop(job.id, None)
        ended = time.time()
        self._events.put(Done(run, disk_full_result(output_dir, began, ended) if full_disk
                              else launch_failure(output_dir, began, ended, problem)))

    def _new_run(self, job: Job, batch: Batch, output_dir: Path, scenario: str, launcher: ForkServer | None,
                 folder_root: tuple[str, str] | None, made_folder: bool, *, startable: bool) -> JobRun | LoopRun:
        """The attempt of a claimed job: driven by the loop when it can be (a built-in job forked by the
        server, a launched command spawned), else in a thread of its own (``--post-run`` hooks, an echoed
        output, or one that will not start: it ends with its launch failure)."""
        echo = self.settings.echo if self.settings.slots == 1 else None
        order = self.hand_over.order
        environment = {RUNNER_ENV: self.identity.id, **attempt_environment(job, batch.options.repeat)}
        turn = (order, order.take())
        run: JobRun | LoopRun
        if startable and launcher is not None and folder_root is not None and not batch.options.post_run:
            run = self._driven[job.id] = ForkedRun(job, batch, output_dir, scenario, launcher, self._events.put,
                                                   cwd=self.settings.cwd, environment=environment,
                                                   folder_root=folder_root, order=turn)
        elif startable and batch.command and echo is None and not batch.options.post_run \
                and self._spawning_allowed():
            run = self._driven[job.id] = SpawnedRun(job, batch, output_dir, scenario, environment=environment,
                                                    order=turn)
        else:
            run = JobRun(job, batch, output_dir, scenario, self._events, cwd=self.settings.cwd, echo=echo,
                         environment=environment, launcher=launcher, made_folder=made_folder,
                         folder_root=folder_root, order=turn)
        return run

    def _spawning_allowed(self) -> bool:
        """Whether launched commands run as :class:`SpawnedRun` here (posix_spawn and process descriptors, in our folder)."""
        if self._can_spawn is None:
            self._can_spawn = loop_can_spawn() and can_spawn_logged(self.settings.cwd)
        return self._can_spawn

    # ------------------------------------------------------------------ leases
    def _heartbeat(self) -> None:
        """Extend the leases of the jobs running and of those whose result waits; stop the lost ones."""
        waiting = self.recorder.unwritten()
        lost = self.leases.heartbeat({*self._runs, *waiting, *(job.id for job in self._waiting)})
        self._unsure_claims = False
        for job in [job for job in self._waiting if job.id in lost]:
            self._waiting.remove(job)
            self.reporter.warn(f"lost the lease on {job.name} before it started; another worker runs it")
        for job_id in sorted(lost):
            run = self._runs.get(job_id) or waiting.get(job_id)
            if run is not None and not run.lost:
                run.lost = True
                self.reporter.warn(f"lost the lease on {run.job.name}; stopping it, another worker runs it")
                run.cancel(grace=0)

    def _sweep(self) -> None:
        if self.leases.sweep():
            self.pacer.wake()

    def _remaining(self) -> int:
        counts = self.store.counts(self.settings.batch_id, shared_only=self.settings.batch_id is None)
        return counts[JobState.QUEUED] + counts[JobState.RUNNING]

    def _cancel_all(self) -> None:
        self._taken_back.update((job.id, job.batch_id) for job in self._waiting)   # claimed, never started: back
        self._waiting.clear()
        if self._force.is_set():
            for run in self._stopping_order():
                run.cancel(grace=0)
        elif not self._cancelling:
            self._cancelling = True
            for run in self._stopping_order():
                run.cancel()

    def _stopping_order(self) -> list[JobRun | LoopRun]:
        """The jobs handed to the fork server ahead first, the next to start first, then the others newest
        first: none of those waiting starts in a slot that frees meanwhile or that a stopped job leaves."""
        runs = list(self._runs.values())
        ahead = [run for run in runs if isinstance(run, ForkedRun) and run.pid is None]
        return ahead + [run for run in reversed(runs) if not (isinstance(run, ForkedRun) and run.pid is None)]

    # ------------------------------------------------------------------ events
    def _wait_for_event(self) -> None:
        now = time.monotonic()
        timeout = _TICK
        if self.pacer.eager and not self._stop.is_set() and len(self._runs) < self.hand_over.holding() \
                and self.backoff.ready(now):
            timeout = 0.0
        due = self.recorder.due()
        if due is not None:                       # wake when a held write is due (and may be written)
            timeout = max(0.0, min(timeout, max(due, self.backoff.retry_at) - now))
        deadline = self._driven_due()
        if deadline is not None:                  # a timeout, a grace, a signalled group to watch
            timeout = max(0.0, min(timeout, deadline - now))
        pause = min(timeout, self.hand_over.linger(self._waiting_at_server(), now)) if timeout else 0.0
        if pause:                                 # the server starts the next jobs itself: let its replies
            self._events.wait(pause)              # gather (see hand_over), only the job threads heard
            timeout = max(0.0, timeout - (time.monotonic() - now))
        self._events.wait(timeout, self._watched())
        for event in self._events.take():
            self._add(event)

    def _waiting_at_server(self) -> int:
        """The jobs handed to the fork server that have not started yet."""
        return sum(1 for run in self._driven.values() if run.pid is None and isinstance(run, ForkedRun))

    def _watched(self) -> dict[int, Callable[[], object]]:
        """What the loop waits on besides its inbox: the fork server's replies, the launched children's ends."""
        watched: dict[int, Callable[[], object]] = {}
        server = self.hand_over.server
        if server is not None and server.fileno() >= 0:      # (-1: a thread of its own reads the replies)
            watched[server.fileno()] = server.poll
        for run in self._driven.values():
            if isinstance(run, SpawnedRun) and run.fileno() >= 0:
                watched[run.fileno()] = functools.partial(self._readable, run)
        return watched

    def _readable(self, run: SpawnedRun) -> None:
        for event in run.on_readable():
            self._events.put(event)

    def _driven_due(self) -> float | None:
        times = [t for t in (run.due() for run in self._driven.values()) if t is not None]
        return min(times) if times else None

    def _tick_driven(self, now: float) -> None:
        """Timeouts and grace periods of the jobs the loop drives (see :mod:`executor.batch.loop_run`)."""
        due = self._driven_due()
        if due is not None and due <= now:
            server = self.hand_over.server       # ends the server told of come first: an ended job
            if server is not None:               # is not timed out (nor its reused pid signalled)
                server.poll()
                for event in self._events.take():
                    self._add(event)
            for run in list(self._driven.values()):
                for event in run.tick(now):
                    self._add(event)

    def _add(self, event: Started | Done | Reply) -> None:
        """A start or an end: shown, and handed to the recorder; an ended job leaves its slot. A reply of
        the fork server on a job the loop drives becomes such events first.

        The display counts a job as running from its start (a job handed to the fork server ahead
        waits for a slot), or from its result when it never started."""
        if isinstance(event, Reply):
            for made in event.run.on_reply(event.message):
                self._add(made)
            return
        job = event.run.job
        if isinstance(event, Done):
            self._runs.pop(job.id, None)
            self._driven.pop(job.id, None)
            if never_started(event.result):       # taken back before its start (a stop, its server's end):
                if not event.run.lost:            # back to the queue, as the jobs claimed and not handed over
                    self._taken_back[job.id] = job.batch_id
                return
        else:
            self.hand_over.started(event.at)
        if isinstance(event, Started) or job.id not in self._shown_running:
            self._shown_running.add(job.id)
            self.reporter.job_started(job)
        if isinstance(event, Done):
            self._shown_running.discard(job.id)
        self.recorder.add(event, time.monotonic())
