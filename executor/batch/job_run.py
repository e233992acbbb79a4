"""One attempt of one job, run in its own thread: prepare the folder, start the child, wait, judge.

The thread never touches the store; it reports ``Started`` and ``Done`` events to the worker loop,
which writes them. Earlier attempts' logs are kept: before attempt n the previous ``log.txt`` becomes
``log.<n-1>.txt``.
"""

from __future__ import annotations

import errno
import os
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO, Protocol

from coverage_engine.results.files import COVERAGE_FILE, LOG_FILE, RESULT_FILE
from executor.batch.builtin_runner import BUILTIN_COMMAND
from executor.batch.fork_errors import ForkServerEnded, JobFolderRefused
from executor.batch.inputs import not_utf8_reason
from executor.batch.launch_template import Launch, substitute
from executor.batch.verdict import (
    FileMark,
    disk_full_result,
    judge,
    launch_failure,
)
from executor.children.hooks import run_post_hooks
from executor.children.process import ChildProcess, Launcher, disk_full
from store.jobs import Batch, Job, JobResult
from store.states import NOT_STARTED_REASON, UNCHARGED_CLAIMS, JobState


class Attempt(Protocol):
    """What the worker and the recorder use of a running attempt: a :class:`JobRun` (a thread) or a
    :class:`~executor.batch.loop_run.LoopRun` (driven by the worker's loop)."""

    job: Job
    batch: Batch
    output_dir: Path
    lost: bool

    def cancel(self, grace: float | None = None) -> None:
        """Stop the attempt (SIGINT, SIGKILL after ``grace``); one not started never starts."""


@dataclass
class Started:
    """The child of ``run`` is running with this process id (also its process group id)."""

    run: Attempt
    pid: int
    #: When the child started (``time.monotonic``): the worker writes the record only once it is this old.
    at: float = field(default_factory=time.monotonic)
    #: The same moment by the wall clock, recorded as the job's start.
    began: float = field(default_factory=time.time)


@dataclass
class Done:
    """The attempt ended; ``result`` is what to record, ``problems`` the post-run hooks that failed."""

    run: Attempt
    result: JobResult
    problems: list[str] = field(default_factory=list)


#: Where the ``--post-run`` hooks of a job write, in the job's folder.
HOOK_LOG = "post_run.log"


def job_marker(job_id: int, attempt: int) -> str:
    """The value of ``$SCENARIO_BATCH_JOB`` in the child of this attempt (``<job id>.<attempt>``)."""
    return f"{job_id}.{attempt}"


#: The errors that mean "no such file" when a path is looked at (those ``Path.exists`` answers False to).
_ABSENT = frozenset({errno.ENOENT, errno.ENOTDIR, errno.EBADF, errno.ELOOP})


def rotate_log(output_dir: Path, attempt: int) -> Path | None:
    """Keep the log of the previous attempt under ``log.<attempt-1>.txt`` before a new attempt starts;
    returns where it went (None: there was none).

    A log of an earlier batch in the same job folder (``--rerun-failed``, a new batch into the same
    ``-o``) is kept too, under the first free ``log.<n>.txt``: nothing written is lost.
    """
    try:
        os.stat(os.path.join(output_dir, LOG_FILE))     # (the common case, none there, without pathlib)
    except OSError as exc:
        if exc.errno in _ABSENT:
            return None
        raise                                   # as Path.exists: a folder that cannot be read is a problem
    log = output_dir / LOG_FILE
    number = max(attempt - 1, 1)
    while (output_dir / f"log.{number}.txt").exists():
        number += 1
    kept = output_dir / f"log.{number}.txt"
    log.replace(kept)
    return kept


def undo_folder(output_dir: Path, kept_log: Path | None, made_folder: bool) -> None:
    """An attempt that never started leaves its folder as it found it: its empty log removed, the
    previous log back in place, the folder removed when this attempt made it and it is empty."""
    log = output_dir / LOG_FILE
    try:
        if log.exists() and log.stat().st_size == 0:
            log.unlink()
        if kept_log is not None and not log.exists():
            kept_log.replace(log)
        if made_folder:
            output_dir.rmdir()
    except OSError:
        pass                                     # not empty (someone wrote there): leave it


def goes_back_unstarted(job: Job) -> bool:
    """Whether an attempt of ``job`` whose fork server ended before it forked the job goes back to the
    queue (as not started, to run on the next server: it never ran), rather than ending as a failure to
    start: within the job's first :data:`~store.states.UNCHARGED_CLAIMS` claims."""
    return job.attempts <= UNCHARGED_CLAIMS


def not_started(output_dir: Path, kept_log: Path | None, made_folder: bool, lost: bool) -> JobResult:
    """The result of an attempt cancelled before its child started: its folder as it was (unless the job
    was lost: its folder may be its next attempt's already)."""
    if not lost:
        undo_folder(output_dir, kept_log, made_folder)
    now = time.time()
    return JobResult(JobState.CANCELLED, None, now, now, reason=NOT_STARTED_REASON, output_dir=str(output_dir))


def attempt_marks(output_dir: Path) -> tuple[FileMark, FileMark]:
    """How ``test.xml`` and ``coverage.json`` look before an attempt (a stale one is not taken as its own)."""
    folder = os.fspath(output_dir)
    return FileMark.of(os.path.join(folder, RESULT_FILE)), FileMark.of(os.path.join(folder, COVERAGE_FILE))


def refuse_unusable(output_dir: Path, scenario_path: str) -> JobResult | None:
    """The result of an attempt that cannot run because its scenario's name is not UTF-8 (said in the
    job's log too, where people look first); None when it can run."""
    unusable = not_utf8_reason(scenario_path)
    if unusable is None:
        return None
    output_dir.mkdir(parents=True, exist_ok=True)
    (output_dir / LOG_FILE).write_text(f"error: {unusable}\n", encoding="utf-8")
    return launch_failure(output_dir, time.time(), time.time(), unusable)


def launch_of(batch: Batch, scenario_path: str, output_dir: Path) -> Launch:
    """What an attempt runs: the batch's launch command, or the built-in runner's (with ``--simulation``)."""
    options = batch.options
    builtin = BUILTIN_COMMAND + (("--simulation", options.simulation) if options.simulation else ())
    return substitute(batch.command or builtin, scenario_path, str(output_dir))


def failed_attempt(output_dir: Path, began: float, exc: OSError) -> JobResult:
    """The result of an attempt whose child could not be started (a full disk stops it instead)."""
    if disk_full(exc):
        return disk_full_result(output_dir, began, time.time())
    what = (exc.strerror or str(exc)) if isinstance(exc, JobFolderRefused) else \
        f"cannot start the launch command: {exc.strerror or exc}"
    return launch_failure(output_dir, began, time.time(), what)


class EventSink(Protocol):
    """Where a job's thread reports (the worker's :class:`~executor.batch.inbox.Inbox`)."""

    def put(self, event: Started | Done) -> None:
        """Hand over one event (from the job's thread)."""


class StartOrder:
    """Lets jobs hand their start over in the order they were claimed.

    Each job runs in its own thread, and those threads race: without this, a job claimed later could
    reach the fork server first and take the free slot (the first job would wait for the next one).
    A job takes a number when it is claimed (:meth:`take`), waits for its turn before it starts
    (:meth:`wait`), and passes the turn on (:meth:`done`) once its request is out, or when it ends
    without one; a number passed on twice, or out of turn, counts once.
    """

    def __init__(self) -> None:
        self._changed = threading.Condition()
        self._issued = 0
        self._next = 0                  # the number whose turn it is
        self._finished: set[int] = set()  # later numbers already done

    def take(self) -> int:
        with self._changed:
            number, self._issued = self._issued, self._issued + 1
            return number

    def wait(self, number: int) -> None:
        with self._changed:
            self._changed.wait_for(lambda: self._next >= number)

    def done(self, number: int) -> None:
        with self._changed:
            if number < self._next:
                return
            self._finished.add(number)
            while self._next in self._finished:
                self._finished.discard(self._next)
                self._next += 1
            self._changed.notify_all()


class JobRun:
    """Run one claimed job in a thread; ``cancel`` stops it (from the worker loop's thread).

    ``order``: the worker's :class:`StartOrder` and this job's number in it (its start is handed over
    in claim order); without it the job starts as soon as its thread is ready.
    """

    def __init__(self, job: Job, batch: Batch, output_dir: Path, scenario_path: str,
                 events: EventSink, *, cwd: str | None = None, echo: BinaryIO | None = None,
                 environment: Mapping[str, str] | None = None, launcher: Launcher | None = None,
                 made_folder: bool = False, order: tuple[StartOrder, int] | None = None,
                 folder_root: tuple[str, str] | None = None) -> None:
        self.job = job
        self.batch = batch
        self.output_dir = output_dir
        self.scenario_path = scenario_path
        self.events = events
        self.cwd = cwd
        self.echo = echo
        self.environment = dict(environment or {})   # for the job's and its hooks' processes (the runner's mark)
        self.launcher = launcher                     # the built-in runner's fork server, for batches without a command
        self.made_folder = made_folder               # the worker made the job's folder for this attempt
        self.folder_root = folder_root               # (root, its real path): the launcher makes the folder
        self.order = order
        self.lost = False                     # set when the lease was taken over: the result is dropped
        self._child: ChildProcess | None = None    # the job's child, then each post-run hook's in turn
        self._lock = threading.Lock()
        self._cancel_grace: float | None = None
        self._thread = threading.Thread(target=self._main, name=f"job-{job.name}", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def join(self, timeout: float | None = None) -> None:
        self._thread.join(timeout)

    def alive(self) -> bool:
        """Whether its thread still runs."""
        return self._thread.is_alive()

    def cancel(self, grace: float | None = None) -> None:
        """Interrupt the child or the running post-run hook (SIGINT to its process group, SIGKILL after
        ``grace``); an attempt or hook not started yet never starts. Safe to call again with a shorter grace."""
        with self._lock:
            self._cancel_grace = self.batch.options.grace if grace is None else grace
            child, grace = self._child, self._cancel_grace
        if child is not None:
            child.cancel(grace)

    def _cancel_requested(self) -> bool:
        with self._lock:
            return self._cancel_grace is not None

    def _track(self, child: ChildProcess | None) -> None:
        """Make ``child`` (a post-run hook's process) the one :meth:`cancel` ends; cancel it if that came first."""
        with self._lock:
            self._child = child
            grace = self._cancel_grace
        if child is not None and grace is not None:
            child.cancel(grace)

    def pass_turn(self) -> None:
        """Let the job claimed after this one hand its start over (its own is out, or never will be)."""
        if self.order is not None:
            self.order[0].done(self.order[1])

    def _main(self) -> None:
        started = time.time()
        problems: list[str] = []
        try:
            try:
                result = self._attempt(problems)
            finally:
                self.pass_turn()              # an attempt that failed before its start passes it on
        except OSError as exc:
            result = failed_attempt(self.output_dir, started, exc)
        except Exception as exc:  # noqa: BLE001 - an attempt must always end with a result
            result = launch_failure(self.output_dir, started, time.time(), f"internal error: {exc!r}")
        self.events.put(Done(self, result, problems))

    def _attempt(self, problems: list[str]) -> JobResult:
        options = self.batch.options
        if self.folder_root is None:             # else the fork server makes it as the job starts
            self.output_dir.mkdir(parents=True, exist_ok=True)
        kept_log = rotate_log(self.output_dir, self.job.attempts)
        mark, coverage_mark = attempt_marks(self.output_dir)
        if not self.batch.command and self.launcher is None:
            raise OSError("the built-in runner is not available")
        refused = refuse_unusable(self.output_dir, self.scenario_path)
        if refused is not None:
            return refused
        launch = launch_of(self.batch, self.scenario_path, self.output_dir)
        child = ChildProcess(list(launch.argv), str(self.output_dir / LOG_FILE), cwd=self.cwd,
                             timeout=options.timeout, grace=options.grace, echo=self.echo,
                             environment={**self.environment, **dict(launch.environment)},
                             marker=job_marker(self.job.id, self.job.attempts),
                             launcher=None if self.batch.command else self.launcher, on_sent=self.pass_turn,
                             log_folder=self.folder_root)
        if self.order is not None:
            self.order[0].wait(self.order[1])
        with self._lock:
            cancelled = self._cancel_grace is not None
            if not cancelled:
                self._child = child               # from now on a cancel reaches it, started or not yet
        # the built-in runner may hold the start back until a slot is free: not under the lock, so
        # that a cancel meanwhile takes it back (start() then returns None)
        try:
            pid = None if cancelled else child.start()
        except ForkServerEnded:
            if not goes_back_unstarted(self.job):
                raise
            pid = None                            # it never ran: back to the queue, for the next server
        finally:
            self.pass_turn()                      # (when the launcher had it, the turn passed already)
        if pid is None:                           # cancelled before it started
            return not_started(self.output_dir, kept_log, self.made_folder, self.lost)
        self.events.put(Started(self, pid))
        outcome = child.wait()
        if options.post_run and not outcome.cancelled:
            problems.extend(run_post_hooks(options.post_run, self.output_dir, log_path=self.output_dir / HOOK_LOG,
                                           cwd=self.cwd, grace=options.grace, cancelled=self._cancel_requested,
                                           track=self._track, environment=self.environment))
        return judge(outcome, self.output_dir, mark, ignore_return_value=options.ignore_return_value,
                     timeout=options.timeout, coverage_mark=coverage_mark)
