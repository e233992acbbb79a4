"""The one atomic file writer: a new temporary file in the same folder, written, then renamed over the target.

A reader (or a crash, Ctrl-C, ``kill -9``) never sees half a file: it sees the old file or the new one.
A link at the target is replaced, never followed. The file gets the mode the process umask gives a new
file (``mkstemp`` makes it 0600; the umask is read once at import, since reading it means setting it).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

_UMASK = os.umask(0o022)
os.umask(_UMASK)


def write_text_atomically(path: str | os.PathLike[str], text: str, *, durable: bool = True) -> Path:
    """Write ``text`` to ``path`` (its folder created if needed); returns the path.

    ``durable``: also flush the file to the disk before the rename, so even a power cut leaves the old or
    the new file. A run's own report skips that (a crash or kill of the process never loses a renamed
    file; a batch of 10,000 runs would wait for 10,000 disk flushes); merged reports keep it.
    A failed write that names no file (a full disk) is raised naming the target.
    """
    target = Path(path)
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
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError) and exc.filename is None:
            raise OSError(exc.errno, exc.strerror, str(target)) from None
        raise
    return target
