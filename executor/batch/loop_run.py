"""One attempt of a job, driven by the worker's own loop: no thread of its own.

A :class:`~executor.batch.job_run.JobRun` is a thread that waits for its child; with thousands of
short jobs those threads, their start-order conditions, timers and queue hand-offs were most of the
batch process's own CPU (measured with trivial jobs at -j 2: a third of the time it held the
interpreter went to waking and switching threads, and as much again to the kernel doing it). A
:class:`LoopRun` needs none of it: it starts its child and then only reacts to what the loop tells
it — the child started, the child ended, a deadline came — turning each into the same ``Started``
and ``Done`` events a thread would have sent. Timeouts and the grace after a signal are deadlines
the loop keeps (:meth:`LoopRun.due`, :meth:`LoopRun.tick`) instead of timer threads.

Two kinds start their child differently:

* :class:`~executor.batch.forked_run.ForkedRun`: a built-in job, forked by the fork server, which
  tells of its start and end (:meth:`ForkServer.submit <executor.batch.builtin_runner.ForkServer.submit>`);
* :class:`~executor.batch.spawned_run.SpawnedRun`: a launched command, started with ``posix_spawn``;
  its end is seen on a process file descriptor (``pidfd_open``) the loop waits on.

What a job sees is the same as on the thread path: its earlier attempt's log kept, SIGTERM at its
timeout and SIGINT when cancelled, each followed by SIGKILL after the grace, which the rest of its
process group gets too; what is left of the group dies with the job. Jobs with ``--post-run`` hooks
or an echoed output (``-j 1``) run on the thread path.
"""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from executor.batch.job_run import (
    Done,
    Started,
    StartOrder,
    attempt_marks,
    failed_attempt,
    job_marker,
    launch_of,
    refuse_unusable,
    rotate_log,
)
from executor.batch.verdict import FileMark, judge, launch_failure
from executor.children.process import JOB_ENV, ProcessOutcome, group_alive, kill_group
from store.jobs import Batch, Job, JobResult

#: Seconds between looks at a signalled job's process group after the job itself ended (its rest has
#: the grace to finish; the job's end waits for that).
GROUP_POLL = 0.02

Events = list[Started | Done]

#: Longest delay between an event and its reading that a stamp may account for (seconds); a stamp
#: further back, or ahead of now, counts as now.
MAX_LAG = 60.0


def moment(at: object) -> tuple[float, float]:
    """``(time.time(), time.monotonic())`` of an event that the process that saw it stamped ``at``
    (``time.monotonic``: one clock for every process of the host, which a change of the wall clock does
    not move), read now: the fork server's replies may wait a while before the worker's loop reads
    them. Without a usable stamp, now."""
    wall, mono = time.time(), time.monotonic()
    if isinstance(at, bool) or not isinstance(at, (int, float)):
        return wall, mono
    lag = mono - at
    if not 0.0 < lag <= MAX_LAG:
        return wall, mono
    return wall - lag, at


class LoopRun:
    """One attempt the worker's loop drives (see the module doc); subclasses start the child.

    ``order``: the worker's start order and this job's number in it (jobs on the thread path wait for
    their turn; this one passes it on once its child is asked for).
    """

    def __init__(self, job: Job, batch: Batch, output_dir: Path, scenario_path: str, *, cwd: str | None,
                 environment: Mapping[str, str], order: tuple[StartOrder, int] | None = None) -> None:
        self.job = job
        self.batch = batch
        self.output_dir = output_dir
        self.scenario_path = scenario_path
        self.cwd = cwd
        self.environment = dict(environment)
        self.order = order
        self.lost = False                      # set when the lease was taken over: the result is dropped
        self.pid: int | None = None
        self._kept_log: Path | None = None
        self._marks: tuple[FileMark, FileMark] | None = None
        self._started_at = 0.0
        self._started_mono = 0.0
        self._cancel_grace: float | None = None   # a cancel came (its grace)
        self._timed_out = False
        self._kill_at: float | None = None     # monotonic time of the SIGKILL a timeout or cancel arranged
        self._killed = False                   # the SIGKILL went out: only the child's end is awaited
        self._look_at: float | None = None     # the child ended, its group not yet: when to look again
        self._ended: tuple[int, float] | None = None   # (return code, when): the job ended, its group may not have
        self._finished = False

    # ------------------------------------------------------------------ start
    def start(self) -> Events:
        """Prepare the attempt and start (or ask for) its child; the events that follow at once."""
        began = time.time()
        try:
            self._kept_log = rotate_log(self.output_dir, self.job.attempts)
            self._marks = attempt_marks(self.output_dir)
            refused = refuse_unusable(self.output_dir, self.scenario_path)
            if refused is not None:
                return [self._done(refused)]
            launch = launch_of(self.batch, self.scenario_path, self.output_dir)
            return self._launch(launch.argv, {**self.environment, **dict(launch.environment),
                                              JOB_ENV: job_marker(self.job.id, self.job.attempts)})
        except OSError as exc:
            return [self._done(failed_attempt(self.output_dir, began, exc))]
        except Exception as exc:  # noqa: BLE001 - an attempt must always end with a result
            return [self._done(launch_failure(self.output_dir, began, time.time(), f"internal error: {exc!r}"))]
        finally:
            self.pass_turn()

    def _launch(self, argv: Sequence[str], environment: Mapping[str, str]) -> Events:
        """Start the child running ``argv`` with ``environment`` added, or ask for it; raises ``OSError``
        when it cannot be."""
        raise NotImplementedError

    def pass_turn(self) -> None:
        if self.order is not None:
            self.order[0].done(self.order[1])

    # ------------------------------------------------------------------ the child's life
    def _on_started(self, pid: int, at: object = None) -> Events:
        """The child started (at ``at``, ``time.monotonic``, when whoever started it said so)."""
        self.pid = pid
        self._started_at, self._started_mono = moment(at)
        if self._cancel_grace is not None:         # the cancel came before the start: stop it now
            self._signal_stop(self._cancel_grace)
        return [Started(self, pid, self._started_mono, self._started_at)]

    def _on_exited(self, returncode: int, at: object = None) -> Events:
        """The child ended (at ``at``, ``time.monotonic``, when whoever reaped it said so)."""
        self._ended = (returncode, moment(at)[0])
        return self.tick(time.monotonic())

    def due(self) -> float | None:
        """When :meth:`tick` has something to do (``time.monotonic``), None when nothing is pending."""
        if self._finished or self.pid is None:
            return None
        if self._ended is not None:            # the group's grace: when to look again
            return self._look_at
        times = [t for t in (None if self._killed else self._kill_at, self._timeout_at()) if t is not None]
        return min(times) if times else None

    def _timeout_at(self) -> float | None:
        timeout = self.batch.options.timeout
        if timeout is None or self._timed_out:
            return None
        return self._started_mono + timeout

    def tick(self, now: float) -> Events:
        """Act on what is due at ``now``: the timeout's SIGTERM (also during a cancel's grace, as on the
        thread path: the verdict is then the timeout), the SIGKILL after the grace, the job's end."""
        if self._finished or self.pid is None:
            return []
        if self._ended is None:
            timeout_at = self._timeout_at()
            if timeout_at is not None and now >= timeout_at:
                self._timed_out = True
                self._signal(signal.SIGTERM)
                self._arm_kill(self.batch.options.grace)
            if self._kill_at is not None and now >= self._kill_at and not self._killed:
                self._kill()
            return []
        # signalled: the rest of the group gets its grace period too, then dies with the job
        if self._kill_at is not None and now < self._kill_at and group_alive(self.pid):
            self._look_at = min(now + GROUP_POLL, self._kill_at)
            return []
        kill_group(self.pid)
        return [self._finish()]

    def _finish(self) -> Done:
        assert self._ended is not None and self._marks is not None
        returncode, finished = self._ended
        outcome = ProcessOutcome(returncode=returncode, started_at=self._started_at, finished_at=finished,
                                 timed_out=self._timed_out, cancelled=self._cancel_grace is not None
                                 and not self._timed_out)
        options = self.batch.options
        return self._done(judge(outcome, self.output_dir, self._marks[0],
                                ignore_return_value=options.ignore_return_value, timeout=options.timeout,
                                coverage_mark=self._marks[1]))

    def _done(self, result: JobResult) -> Done:
        self._finished = True
        self._closed()
        return Done(self, result)

    def _closed(self) -> None:
        """The attempt has its result: let go of what watched the child."""

    # ------------------------------------------------------------------ stopping
    def cancel(self, grace: float | None = None) -> None:
        """Stop the attempt: a start not made yet is taken back; a started child gets SIGINT, and SIGKILL
        after ``grace`` (at once when 0), as does what is left of its group after the child ended. Safe
        to call again with a shorter grace."""
        grace = self.batch.options.grace if grace is None else grace
        first = self._cancel_grace is None
        if not first and grace >= (self._cancel_grace or 0.0):
            return
        self._cancel_grace = grace
        if self._finished:
            return
        if self.pid is None:
            if first:
                self._take_back()
            return
        if self._ended is None:
            self._signal_stop(grace)
        else:                                      # the group's grace: cut short (or at once)
            self._arm_kill(max(grace, 0.0))
            self._look_at = self._kill_at
            if grace <= 0:
                kill_group(self.pid)

    def _take_back(self) -> None:
        """A cancel before the child started: withdraw the request (a started child is stopped instead)."""

    def abandon(self) -> None:
        """The worker's loop failed: the child was sent SIGKILL (:meth:`cancel`); let go of it."""

    def _signal_stop(self, grace: float) -> None:
        if grace <= 0:
            self._kill_at = time.monotonic()
            self._kill()
            return
        self._signal(signal.SIGINT)
        self._arm_kill(grace)

    def _kill(self) -> None:
        self._killed = True
        self._signal(signal.SIGKILL)

    def _arm_kill(self, grace: float) -> None:
        deadline = time.monotonic() + grace
        if self._kill_at is None or deadline < self._kill_at:
            self._kill_at = deadline

    def _signal(self, sig: int) -> None:
        """``sig`` to the child's group; to the child itself when it has no group yet (a job forked an
        instant ago has not made its own session: the signal waits, blocked, until it has)."""
        assert self.pid is not None
        if not kill_group(self.pid, sig) and self._ended is None:
            try:
                os.kill(self.pid, sig)
            except OSError:
                pass

    def alive(self) -> bool:
        """False: no thread of its own to wait for (the worker asks every run alike)."""
        return False

    def join(self, timeout: float | None = None) -> None:
        """Nothing to join (see :meth:`alive`)."""
