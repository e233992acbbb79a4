"""The sizes every input is bounded by, in one place (docs/security.md lists them).

A module that imports only the standard library's ``os`` and ``stat``, so that a command's start (which must not
import yaml) can read them.
"""

from __future__ import annotations

import os
import stat

#: Largest YAML text read (a parameter file, a ``.sce`` file, a coverage plan), in bytes.
MAX_YAML_BYTES = 64 * 1024 * 1024

#: Largest scenario or library file (``.osc``) read, in bytes; a bigger one is refused before it is read.
MAX_SOURCE_BYTES = 64 * 1024 * 1024

#: Most nodes a YAML document may stand for with its aliases expanded.
MAX_EXPANDED_NODES = 1_000_000

#: Most bytes of scalar text a YAML document may stand for with its aliases expanded.
MAX_EXPANDED_BYTES = 64 * 1024 * 1024


def mib(size: int) -> str:
    """``64 MiB``: a limit as messages say it."""
    return f"{size // (1024 * 1024)} MiB"


def read_bounded(path: str | os.PathLike[str], limit: int) -> bytes | None:
    """The bytes of the regular file ``path`` when it holds at most ``limit``; None when it is missing, a
    symbolic link (never followed), not a regular file (a FIFO is not waited on), larger, or unreadable.

    For the small files a results folder carries beside its report (``declared.json``, ``history.json``,
    ``search.json``): a report goes on without one rather than trust what it cannot read safely.
    """
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    except OSError:
        return None
    try:
        with os.fdopen(fd, "rb") as handle:
            if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
                return None
            data = handle.read(limit + 1)
    except OSError:
        return None
    return data if len(data) <= limit else None
