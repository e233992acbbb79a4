"""Start a command whose output goes to a log, the log opened by the child itself (``posix_spawn``).

``subprocess.Popen`` needs the log open in the parent to hand it over; creating a file is a
file-system transaction whose CPU the creating process pays (measured on ext4 under load: 0.4-0.6 ms,
more than all the rest a batch runner does to start a job). ``os.posix_spawnp`` with an ``open``
file action makes the child open it between its (v)fork and its ``exec``, so that work is the
child's, and a runner starting thousands of short jobs is not held up by it.

What :func:`spawn_logged` does is what ``ChildProcess`` asked of ``Popen``: its own session (a new
process group), stdin from ``/dev/null``, stdout and stderr into the log (truncated, or appended to),
the given environment, and the parent's working directory. Descriptors are not closed one by one
(``close_fds``): Python opens every descriptor non-inheritable, as do SQLite and the store's drivers,
so none reaches the child. A command that cannot be run raises ``OSError`` here, as ``Popen`` does.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Mapping, Sequence


class SpawnedProcess:
    """A child started by :func:`spawn_logged`: the subset of ``subprocess.Popen`` that ChildProcess uses."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.stdout = None
        self.returncode: int | None = None
        self._lock = threading.Lock()

    def poll(self) -> int | None:
        return self.returncode

    def wait(self) -> int:
        """Wait for the child's end (from one thread at a time) and return its exit code (``-signal`` if killed)."""
        with self._lock:
            if self.returncode is None:
                _, status = os.waitpid(self.pid, 0)
                self.returncode = os.waitstatus_to_exitcode(status)
            return self.returncode


def spawn_logged(argv: Sequence[str], log_path: str, *, append: bool,
                 extra_environment: Mapping[str, str]) -> SpawnedProcess:
    """Start ``argv`` (looked up on ``PATH``) in a new session with stdout and stderr on ``log_path``, in this
    process's environment plus ``extra_environment`` (built from ``os.environb``: no decoding of every entry)."""
    environment = dict(os.environb)
    environment.update((os.fsencode(key), os.fsencode(value)) for key, value in extra_environment.items())
    mode = os.O_WRONLY | os.O_CREAT | (os.O_APPEND if append else os.O_TRUNC)
    actions = [(os.POSIX_SPAWN_OPEN, 0, os.devnull, os.O_RDONLY, 0),
               (os.POSIX_SPAWN_OPEN, 1, log_path, mode, 0o666),
               (os.POSIX_SPAWN_DUP2, 1, 2)]
    pid = os.posix_spawnp(argv[0], list(argv), environment, file_actions=actions, setsid=True)
    return SpawnedProcess(pid)


def can_spawn_logged(cwd: str | None) -> bool:
    """Whether :func:`spawn_logged` can start a child in ``cwd`` (it runs in the parent's folder only)."""
    if not hasattr(os, "posix_spawnp"):
        return False
    if cwd is None:
        return True
    try:
        return os.path.samefile(cwd, ".")
    except OSError:
        return False
