"""One writer per output folder: ``scenario_variation -o`` and ``scenario_batch_execution -o`` hold a lock.

Two variation runs into one folder used to both exit 0 while the store lost most of their rows; two
batches on one ``-o`` ran every job twice in the same job folders. The lock is the file
``.scenario-lock`` in the folder, locked with ``flock`` for as long as the command runs: the kernel
drops the lock when the process ends however it ends (kill -9 included), so a lock is never stale.
The holder writes who it is (pid, host, command, since when) into the file, and a refused second
writer says exactly that, or with ``--wait`` waits until the folder is free.

``flock`` is local to a host (and to file systems that honour it); batches that share a folder across
hosts coordinate through the store (``--resume``, ``worker``), which is not locked here.
"""

from __future__ import annotations

import json
import os
import socket
import time
from collections.abc import Callable
from pathlib import Path

LOCK_NAME = ".scenario-lock"
#: Seconds between two looks while ``--wait`` waits for the folder.
POLL_SECONDS = 0.5


class FolderBusy(Exception):
    """Another process writes into the folder; the message names it."""


class FolderLock:
    """The lock of one output folder; ``acquire`` then, at the end, ``release`` (or use ``with``)."""

    def __init__(self, folder: str | os.PathLike[str], command: str) -> None:
        self.folder = Path(folder)
        self.command = command
        self._fd: int | None = None

    def acquire(self, wait: bool = False, on_wait: Callable[[str], object] | None = None) -> FolderLock:
        """Take the lock; :class:`FolderBusy` naming the holder, unless ``wait`` (then wait until it is free)."""
        import fcntl

        self.folder.mkdir(parents=True, exist_ok=True)
        path = self.folder / LOCK_NAME
        fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0), 0o644)
        announced = False
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                holder = _describe(fd)
                if not wait:
                    os.close(fd)
                    raise FolderBusy(f"{self.folder}/ is being written by {holder}; wait for it to end, "
                                     "or pass --wait to wait for it") from None
                if not announced and on_wait is not None:
                    on_wait(f"waiting for {self.folder}/: it is being written by {holder}")
                    announced = True
                time.sleep(POLL_SECONDS)
        info = {"pid": os.getpid(), "host": socket.gethostname(), "command": self.command, "since": time.time()}
        os.ftruncate(fd, 0)
        os.pwrite(fd, (json.dumps(info) + "\n").encode("utf-8"), 0)
        self._fd = fd
        return self

    def release(self) -> None:
        """Let the next writer in (closing the file drops the lock)."""
        if self._fd is not None:
            try:
                os.ftruncate(self._fd, 0)
            except OSError:
                pass
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> FolderLock:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.release()


def _describe(fd: int) -> str:
    """Who holds the lock, from what it wrote into the file."""
    try:
        data = json.loads(os.pread(fd, 4096, 0).decode("utf-8", "replace") or "{}")
    except ValueError:
        data = {}
    if not isinstance(data, dict) or "pid" not in data:
        return "another process"
    since = data.get("since")
    when = time.strftime(" since %H:%M:%S", time.localtime(since)) if isinstance(since, (int, float)) else ""
    return f"{data.get('command', 'a command')} (pid {data['pid']} on {data.get('host', '?')}{when})"

