"""Write a text file atomically: a new temporary file in the same folder, flushed, then renamed over the target.

A reader (or a crash) never sees half a file, and a link at the target is replaced, never followed.
A user's ``-o`` goes through :func:`write_output`: a target that exists and is not a regular file (``/dev/null``, ``/dev/stdout``, a FIFO, a terminal) is
written in place and never replaced: renaming a temporary file over ``/dev/null`` as root would turn
the device into a regular file for every process of the machine. ``-`` is standard output.
"""

from __future__ import annotations

import os
import stat
import sys
import tempfile
from pathlib import Path

_UMASK = os.umask(0o022)
os.umask(_UMASK)

#: The output name that means standard output.
STDOUT = "-"


def write_output(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` where a user's ``-o`` names: ``-`` is standard output, a device or FIFO is written
    in place, anything else is replaced atomically (:func:`write_text_atomically`)."""
    target = Path(path)
    if str(path) == STDOUT:
        sys.stdout.write(text)
        sys.stdout.flush()
        return target
    if _special(target):
        try:
            _write_in_place(target, text)
        except OSError as exc:
            raise OSError(exc.errno, exc.strerror, str(target)) from None
        return target
    return write_text_atomically(target, text)


def write_text_atomically(path: str | os.PathLike[str], text: str, *, durable: bool = True) -> Path:
    """Write ``text`` to ``path`` under a temporary name and rename it into place; returns the path.

    ``durable``: flush the file to the disk before the rename, so even a power cut leaves the old or the
    new file. An error that names no file (a full disk) is raised naming ``path``.
    """
    target = Path(path)
    try:
        _replace(target, text, durable)
    except OSError as exc:
        if exc.filename is None:
            raise OSError(exc.errno, exc.strerror, str(target)) from None
        raise
    return target


def _special(target: Path) -> bool:
    """Whether ``target`` exists (through links) and is not a regular file or a folder."""
    try:
        mode = os.stat(target).st_mode
    except OSError:
        return False
    return not stat.S_ISREG(mode) and not stat.S_ISDIR(mode)


def _write_in_place(target: Path, text: str) -> None:
    """Open without waiting (a FIFO nobody reads is an error, not a hang), then write blocking."""
    fd = os.open(target, os.O_WRONLY | os.O_NOCTTY | os.O_NONBLOCK)
    os.set_blocking(fd, True)
    with os.fdopen(fd, "w", encoding="utf-8") as handle:
        handle.write(text)


def _replace(target: Path, text: str, durable: bool) -> None:
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent)
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
            handle.flush()
            if durable:
                os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
