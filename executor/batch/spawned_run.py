"""A launched command the worker's loop drives (see :mod:`executor.batch.loop_run`).

The child is started with ``posix_spawn`` (:func:`~executor.children.spawn.spawn_logged`: its own
session, its output into the job's log, which the child opens), and its end is seen on a process file
descriptor (``os.pidfd_open``) that the loop waits on with everything else; the loop then reaps it.
Where the system has no process descriptors the run looks for its end every
:data:`~executor.batch.loop_run.GROUP_POLL` seconds instead.
"""

from __future__ import annotations

import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from coverage_engine.results.files import LOG_FILE
from executor.batch.job_run import StartOrder
from executor.batch.loop_run import GROUP_POLL, Events, LoopRun
from executor.children.spawn import spawn_logged
from store.jobs import Batch, Job


def loop_can_spawn() -> bool:
    """Whether this system lets the loop start and watch launched commands (``posix_spawn`` and ``pidfd_open``)."""
    return hasattr(os, "posix_spawnp") and hasattr(os, "pidfd_open")


class SpawnedRun(LoopRun):
    """One attempt of a launched command: spawned at once, its end read from its process descriptor."""

    def __init__(self, job: Job, batch: Batch, output_dir: Path, scenario_path: str, *,
                 environment: Mapping[str, str], order: tuple[StartOrder, int] | None = None) -> None:
        super().__init__(job, batch, output_dir, scenario_path, cwd=None, environment=environment, order=order)
        self._pidfd: int | None = None

    def _launch(self, argv: Sequence[str], environment: Mapping[str, str]) -> Events:
        pid = spawn_logged(argv, os.path.join(self.output_dir, LOG_FILE), append=False, extra_environment=environment).pid
        try:
            self._pidfd = os.pidfd_open(pid)
        except OSError:
            self._pidfd = None                 # no process descriptors here: looked for every GROUP_POLL
        return self._on_started(pid)

    def fileno(self) -> int:
        """The descriptor that becomes readable when the child ends (-1: none, see :meth:`due`)."""
        return -1 if self._pidfd is None else self._pidfd

    def on_readable(self) -> Events:
        """The child may have ended: reap it, and go on to its end."""
        if self._finished or self.pid is None or self._ended is not None:
            return []
        try:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
        except ChildProcessError:
            pid, status = self.pid, 0          # reaped elsewhere: its status is lost
        if pid == 0:
            return []
        if self._pidfd is not None:
            os.close(self._pidfd)
            self._pidfd = None
        return self._on_exited(os.waitstatus_to_exitcode(status))

    def due(self) -> float | None:
        if self._pidfd is None and self.pid is not None and self._ended is None and not self._finished:
            polled = time.monotonic() + GROUP_POLL
            due = super().due()
            return polled if due is None else min(due, polled)
        return super().due()

    def tick(self, now: float) -> Events:
        if self._ended is None:                # an end not read yet comes first: no timeout for a child that ended
            ended = self.on_readable()
            if ended:
                return ended
        return super().tick(now)

    def abandon(self) -> None:
        """Reap the killed child (a few seconds at most) and close its descriptor: no zombie, no open pidfd."""
        end = time.monotonic() + 5.0
        while self.pid is not None and self._ended is None and not self._finished and time.monotonic() < end:
            if self.on_readable():
                break
            time.sleep(GROUP_POLL)
        self._closed()

    def _closed(self) -> None:
        if self._pidfd is not None:
            os.close(self._pidfd)
            self._pidfd = None
