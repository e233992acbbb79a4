"""Write many small files, optionally in a forked helper process.

Creating a file costs tens of microseconds of kernel time on common file systems (more on ext4 with
``discard`` or under load); for 100,000 variants that alone is several seconds. Threads do not help
(creations in one directory serialise on its lock, and each file would need the GIL back). So for
large generations a forked child does the ``open``/``write``/``close`` calls while the parent renders
the next texts and fills the store: the two run on different cores.

The parent sends ``(path, bytes)`` records through a pipe in ~1 MB batches. If the child fails (disk
full, permission), :meth:`FileWriter.close` raises :class:`OSError` with its message. The child
ignores SIGINT and SIGTERM: on Ctrl-C the parent stops sending, and the child still writes every
file it was sent (whose store rows the parent has committed) before it ends.
"""

from __future__ import annotations

import os
import signal
import struct
import sys

_HEADER = struct.Struct("!II")
#: ``O_NOFOLLOW``: a symbolic link planted under a variant's name is never written through.
_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_BINARY", 0) | getattr(os, "O_NOFOLLOW", 0)
_BATCH = 1 << 20


def write_file(path: str, data: bytes) -> None:
    """Write ``data`` to ``path`` (created or truncated), all of it."""
    fd = os.open(path, _FLAGS, 0o644)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
    finally:
        os.close(fd)


class FileWriter:
    """``write(path, data)`` now (in process) or soon (in a forked child, ``background=True``)."""

    def __init__(self, background: bool = False) -> None:
        self._pid = 0
        self._pending: list[bytes] = []
        self._size = 0
        if background and hasattr(os, "fork"):
            self._start()

    def _start(self) -> None:
        read_end, self._pipe = os.pipe()
        error_read, error_write = os.pipe()
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:  # pragma: no cover - runs in the child (coverage does not follow forks)
            # Ctrl-C reaches the whole process group: the parent decides when to stop, and the child
            # writes every file it was given before it ends (the parent closes the pipe).
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
            os.close(self._pipe)
            os.close(error_read)
            code = 0
            try:
                _serve(read_end)
            except BaseException as exc:  # noqa: BLE001 - reported to the parent
                os.write(error_write, str(exc).encode("utf-8", "replace")[:4000])
                code = 1
            os._exit(code)
        os.close(read_end)
        os.close(error_write)
        self._pid, self._errors = pid, error_read

    def write(self, path: str, data: bytes) -> None:
        if not self._pid:
            write_file(path, data)
            return
        encoded = path.encode("utf-8", "surrogateescape")
        self._pending += [_HEADER.pack(len(encoded), len(data)), encoded, data]
        self._size += len(encoded) + len(data) + _HEADER.size
        if self._size >= _BATCH:
            self._flush()

    def _flush(self) -> None:
        if not self._pending:
            return
        view = memoryview(b"".join(self._pending))
        self._pending, self._size = [], 0
        try:
            while view:
                view = view[os.write(self._pipe, view):]
        except BrokenPipeError:
            self._finish()  # raises the child's error
            raise

    def close(self) -> None:
        """Wait until every file is written; raises :class:`OSError` if one could not be."""
        if self._pid:
            try:
                self._flush()
            finally:
                self._finish()

    def _finish(self) -> None:
        if not self._pid:
            return
        os.close(self._pipe)
        _pid, status = os.waitpid(self._pid, 0)
        self._pid = 0
        message = os.read(self._errors, 4000).decode("utf-8", "replace")
        os.close(self._errors)
        if os.waitstatus_to_exitcode(status) != 0:
            raise OSError(message or "the file writer process failed")

    def __enter__(self) -> FileWriter:
        return self

    def __exit__(self, exc_type, exc, traceback) -> None:
        if exc_type is None:
            self.close()
            return
        try:  # an error is on its way already: wait for the child, but do not hide that error
            self.close()
        except OSError:
            pass


def _serve(fd: int) -> None:  # pragma: no cover - runs in the child
    """Read records from ``fd`` until end of file and write them."""
    buffer = bytearray()
    position = 0
    while True:
        chunk = os.read(fd, _BATCH)
        if not chunk:
            break
        buffer += chunk
        while len(buffer) - position >= _HEADER.size:
            path_len, data_len = _HEADER.unpack_from(buffer, position)
            end = position + _HEADER.size + path_len + data_len
            if len(buffer) < end:
                break
            start = position + _HEADER.size
            path = bytes(buffer[start:start + path_len]).decode("utf-8", "surrogateescape")
            write_file(path, bytes(buffer[start + path_len:end]))
            position = end
        if position:
            del buffer[:position]
            position = 0
