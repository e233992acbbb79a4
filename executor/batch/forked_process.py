"""The worker's side of one job forked by the fork server (:mod:`executor.batch.builtin_runner`).

:class:`ForkedProcess` stands for the job's process where :class:`executor.children.process.ChildProcess`
expects a ``subprocess.Popen`` (its end comes as the server's ``exited`` reply, not from ``wait``);
:class:`Pending` is a :meth:`~executor.batch.builtin_runner.ForkServer.spawn` waiting for the server's
answer.
"""

from __future__ import annotations

import subprocess
import threading
from typing import BinaryIO


class ForkedProcess:
    """A job forked by the server, with the subset of ``subprocess.Popen`` that ChildProcess uses."""

    def __init__(self, pid: int, stdout: BinaryIO | None = None) -> None:
        self.pid = pid
        self.stdout = stdout
        self.returncode: int | None = None
        self._done = threading.Event()

    def _exited(self, returncode: int) -> None:
        self.returncode = returncode
        self._done.set()

    def poll(self) -> int | None:
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        if not self._done.wait(timeout):
            raise subprocess.TimeoutExpired(str(self.pid), timeout or 0)
        assert self.returncode is not None
        return self.returncode


class Pending:
    """A spawn request waiting for the server's answer."""

    def __init__(self) -> None:
        self.event = threading.Event()
        self.pid: int | None = None
        self.reason: str | None = None
        self.errno: int | None = None              # why the server could not start it, as an OSError's
        self.folder_refused = False                # … because the job's folder could not be made
        self.withdrawn = False
        self.gone = False                          # the server ended before it answered
