"""A built-in job the worker's loop drives: its child forked by the fork server (see :mod:`executor.batch.loop_run`).

The request goes out with :meth:`ForkServer.submit <executor.batch.builtin_runner.ForkServer.submit>`
(kept until the worker has started what it can, then sent with the others in one message);
the server makes the job's folder and opens its log as the job starts, and tells of the start and
the end. Its replies are read by the worker's loop and reach the run as :class:`Reply` events.
"""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from coverage_engine.results.files import LOG_FILE
from executor.batch.builtin_runner import ForkServer
from executor.batch.fork_errors import ForkServerEnded, start_failure
from executor.batch.job_run import Done, StartOrder, failed_attempt, goes_back_unstarted, not_started
from executor.batch.loop_run import Events, LoopRun
from executor.children.process import kill_orphan
from store.jobs import Batch, Job


@dataclass(frozen=True)
class Reply:
    """A message of the fork server on ``run``'s request, handed to the worker's loop."""

    run: ForkedRun
    message: dict


class ForkedRun(LoopRun):
    """One built-in attempt: its request to the fork server, then the server's replies."""

    def __init__(self, job: Job, batch: Batch, output_dir: Path, scenario_path: str, server: ForkServer,
                 deliver: Callable[[Reply], None], *, cwd: str | None, environment: Mapping[str, str],
                 folder_root: tuple[str, str], order: tuple[StartOrder, int] | None = None) -> None:
        super().__init__(job, batch, output_dir, scenario_path, cwd=cwd, environment=environment, order=order)
        self.server = server
        self.deliver = deliver
        self.folder_root = folder_root
        self._request: str | None = None

    def _launch(self, argv: Sequence[str], environment: Mapping[str, str]) -> Events:
        try:
            self._request = self.server.submit(argv, cwd=self.cwd, environment=environment,
                                               log_path=os.path.join(os.path.abspath(self.output_dir), LOG_FILE),
                                               append=False, log_folder=self.folder_root, reply=self._reply, later=True)
        except ForkServerEnded:
            return [self._server_ended()]
        return []

    def _reply(self, message: dict) -> None:
        """From the fork server's reader (the worker's loop): on to the loop's events."""
        self.deliver(Reply(self, message))

    def on_reply(self, message: dict) -> Events:
        """The events one reply of the server makes."""
        event = message.get("event")
        if self._finished:
            return []
        if event == "started":
            return self._on_started(int(message["pid"]), message.get("at"))
        if event == "exited":
            return self._on_exited(os.waitstatus_to_exitcode(int(message["status"])), message.get("at"))
        if event == "withdrawn":
            return [self._not_started()]
        if event == "failed":
            return [self._failed(message)]
        if self.pid is None:                       # "gone" before the start: the job never ran
            return [self._server_ended()]
        kill_orphan(self.pid, self.server.mark)    # its parent is gone: nobody else can wait for it
        return self._on_exited(-signal.SIGKILL)

    def _failed(self, message: dict) -> Done:
        """A job the server could not start: the result the thread path gives the same failure."""
        failure = start_failure(message.get("reason"), message.get("errno"), bool(message.get("folder")))
        return self._done(failed_attempt(self.output_dir, time.time(), failure))

    def _server_ended(self) -> Done:
        """The server ended before it forked the job: the job never ran, and goes back to the queue for
        the next server (as not started), within its first ``UNCHARGED_CLAIMS`` claims."""
        if goes_back_unstarted(self.job):
            return self._not_started()
        return self._failed({"reason": "the fork server ended"})

    def _not_started(self) -> Done:
        return self._done(not_started(self.output_dir, self._kept_log, False, self.lost))

    def _take_back(self) -> None:
        if self._request is not None:
            self.server.withdraw(self._request)
