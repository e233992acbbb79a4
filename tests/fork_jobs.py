"""Requests sent to a real fork server and the replies heard, for the fork server's tests.

:class:`Jobs` submits ``scenario_execution`` requests (each job's output under ``out/j<job>``) and keeps
every reply in the order it came; :func:`job_folder` makes the folder they run in, with a quick, a
slow and a hanging scenario.
"""

from __future__ import annotations

import os
import select
import time
from pathlib import Path

import pytest

from executor.batch.builtin_runner import ForkServer

QUICK = "import osc.helpers\n\nscenario quick:\n    do serial:\n        log('hi')\n        emit end\n"
SLOW = "import osc.helpers\n\nscenario slow:\n    do serial:\n        wait elapsed({seconds}s)\n        emit end\n"


def parent_of(pid: int) -> int:
    with open(f"/proc/{pid}/stat") as handle:
        return int(handle.read().rsplit(")", 1)[1].split()[1])


class Jobs:
    """Requests submitted to a server, and every reply in the order it came."""

    def __init__(self, server: ForkServer, folder: Path) -> None:
        self.server, self.folder = server, folder
        self.replies: list[tuple[int, str, int | None]] = []    # (job, event, pid)
        self.parents: dict[int, int] = {}                       # job -> the process that forked it
        self.requests: dict[int, str] = {}
        self.messages: list[dict] = []                          # the replies themselves

    def submit(self, job: int, scenario: str, later: bool = False) -> None:
        out = self.folder / "out" / f"j{job}"
        root = str(self.folder / "out")
        self.requests[job] = self.server.submit(
            ["scenario_execution", scenario, "--output-dir", str(out)], cwd=str(self.folder), environment={},
            log_path=str(out / "log.txt"), append=False, log_folder=(root, os.path.realpath(root)),
            reply=lambda message: self._heard(job, message), later=later)

    def _heard(self, job: int, message: dict) -> None:
        self.replies.append((job, str(message.get("event")), message.get("pid")))
        self.messages.append(message)
        if message.get("event") == "started":
            try:
                self.parents[job] = parent_of(int(message["pid"]))
            except OSError:
                pass                         # a quick job may have ended and been reaped already

    def events(self, kind: str) -> list[int]:
        return [job for job, event, _pid in self.replies if event == kind]

    def wait_for_starts(self, count: int, seconds: float = 60) -> None:
        """Read replies until ``count`` requests have started."""
        deadline = time.monotonic() + seconds
        while len(self.events("started")) < count:
            assert time.monotonic() < deadline, self.replies
            select.select([self.server.fileno()], [], [], 0.2)
            self.server.poll()

    def wait_for(self, done: int, seconds: float = 60) -> None:
        """Read replies until ``done`` requests have had their last word (or the server ended)."""
        deadline = time.monotonic() + seconds
        while len([r for r in self.replies if r[1] in ("exited", "withdrawn", "failed", "gone")]) < done:
            assert time.monotonic() < deadline, self.replies
            select.select([self.server.fileno()], [], [], 0.2)
            if not self.server.poll():
                return


def job_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """``tmp_path`` with ``out/``, ``quick.osc``, ``slow.osc`` (1.5 s) and ``hang.osc`` (60 s); the
    server's scratch folder goes under it too."""
    monkeypatch.setenv("TMPDIR", str(tmp_path / "tmp"))     # the server's scratch folder goes here
    (tmp_path / "tmp").mkdir()
    (tmp_path / "out").mkdir()
    (tmp_path / "quick.osc").write_text(QUICK)
    (tmp_path / "slow.osc").write_text(SLOW.format(seconds=1.5))
    (tmp_path / "hang.osc").write_text(SLOW.format(seconds=60))
    return tmp_path
