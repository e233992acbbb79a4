"""Write many small files, optionally in a forked helper process, each one whole or not at all.

Creating a file costs tens of microseconds of kernel time on common file systems (more on ext4 with
``discard`` or under load); for 100,000 variants that alone is several seconds. Threads do not help
(creations in one directory serialise on its lock, and each file would need the GIL back). So for
large generations a forked child does the ``open``/``write``/``rename`` calls while the parent renders
the next texts and fills the store: the two run on different cores.

A file that replaces another (an earlier generation's) is written under a temporary name beside it
(``.<name>.part``, created without following links) and renamed over the final name, so a full disk or
a kill leaves the old file whole. A new file is created exclusively under its own name (``O_EXCL``,
never through a link) and removed again if it cannot be written whole: one metadata operation instead
of two, which is most of the cost of 100,000 small files. Either way no cut-short file is left under a
variant's name after an error, and nothing is written through a planted symbolic link. :meth:`FileWriter.checkpoint` and
:meth:`FileWriter.wait` let the caller learn when everything written before a checkpoint is on disk,
so it records files only once they exist.

The parent sends ``(path, bytes)`` records through a pipe in ~1 MB batches; a checkpoint is a record
with an empty path, answered with one byte on a second pipe. If the child fails (disk full,
permission) it reports the errno and path, and the next :meth:`~FileWriter.wait` or
:meth:`~FileWriter.close` raises that :class:`OSError`. The child ignores SIGINT and SIGTERM: on
Ctrl-C the parent stops sending, and the child still writes every file it was sent before it ends.
"""

from __future__ import annotations

import errno
import json
import os
import signal
import struct
import sys
from types import TracebackType

_HEADER = struct.Struct("!IIB")     # path length, data length, 1 = replaces an existing file
#: ``O_NOFOLLOW``: a symbolic link planted under a temporary name is never written through.
_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_BINARY", 0) | getattr(os, "O_NOFOLLOW", 0)
#: A new file: created here, never opened if anything (a link included) is already there.
_NEW_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0) | getattr(os, "O_NOFOLLOW", 0)
_BATCH = 1 << 20
#: Suffix of the temporary name a file is written under before it is renamed to its own.
PART_SUFFIX = ".part"


def temporary_name(path: str) -> str:
    """``dir/.name.part`` for ``dir/name``: hidden, and never matched as a variant (``*.sce``)."""
    head, tail = os.path.split(path)
    return os.path.join(head, f".{tail}{PART_SUFFIX}")


def write_file(path: str, data: bytes, replace: bool = True) -> None:
    """Make ``path`` hold ``data``, all of it or (on any error) none of it; raises :class:`OSError`.

    ``replace``: the data goes to a temporary name first, which is renamed over ``path`` (a link at
    ``path`` is replaced, not followed; a failure leaves whatever was at ``path`` before). Otherwise
    ``path`` must not exist yet: it is created exclusively, and removed again on a failure (should
    something have appeared there meanwhile, the replacing way is taken).
    """
    if not replace:
        try:
            fd = os.open(path, _NEW_FLAGS, 0o644)
        except FileExistsError:
            return write_file(path, data, replace=True)
        _fill(fd, data, path, remove=path)
        return
    part = temporary_name(path)
    try:
        fd = os.open(part, _FLAGS, 0o644)
    except OSError as exc:
        if exc.errno not in (errno.ELOOP, errno.EMLINK):
            raise
        os.unlink(part)  # a link planted under the temporary name: remove the link itself, then create
        fd = os.open(part, _FLAGS, 0o644)
    _fill(fd, data, path, remove=part)
    try:
        os.replace(part, path)
    except OSError:
        _unlink_quietly(part)
        raise


def _fill(fd: int, data: bytes, path: str, remove: str) -> None:
    """Write all of ``data`` to ``fd`` and close it; on a failure remove ``remove`` (the file being made)
    and raise an :class:`OSError` naming ``path`` (``os.write`` names no file)."""
    try:
        try:
            _write_all(fd, data)
        finally:
            os.close(fd)
    except OSError as exc:
        _unlink_quietly(remove)
        raise OSError(exc.errno, exc.strerror, path) from None


def _unlink_quietly(path: str) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


class FileWriter:
    """``write(path, data)`` now (in process) or soon (in a forked child, ``background=True``)."""

    def __init__(self, background: bool = False) -> None:
        self._pid = 0
        self._pending: list[bytes] = []
        self._size = 0
        self._checkpoints = self._confirmed = 0
        self._error: OSError | None = None
        if background and hasattr(os, "fork"):
            self._start()

    def _start(self) -> None:
        read_end, self._pipe = os.pipe()
        _widen(self._pipe)
        ack_read, ack_write = os.pipe()
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:  # pragma: no cover - runs in the child (coverage does not follow forks)
            # Ctrl-C reaches the whole process group: the parent decides when to stop, and the child
            # writes every file it was given before it ends (the parent closes the pipe).
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
            os.close(self._pipe)
            os.close(ack_read)
            code = 0
            try:
                _serve(read_end, ack_write)
            except BaseException as exc:  # noqa: BLE001 - reported to the parent
                report = {"errno": getattr(exc, "errno", None), "strerror": getattr(exc, "strerror", None),
                          "filename": getattr(exc, "filename", None), "text": str(exc)}
                _write_all(ack_write, b"E" + json.dumps(report).encode("utf-8", "replace")[:8000])
                code = 1
            os._exit(code)
        os.close(read_end)
        os.close(ack_write)
        self._pid, self._acks = pid, ack_read

    def write(self, path: str, data: bytes, replace: bool = True) -> None:
        """Write ``data`` to ``path`` (now, or in the child soon); raises :class:`OSError` when it cannot.

        ``replace`` False promises that nothing is at ``path`` yet (see :func:`write_file`)."""
        if not self._pid:
            write_file(path, data, replace)
            return
        encoded = path.encode("utf-8", "surrogateescape")
        self._pending += [_HEADER.pack(len(encoded), len(data), int(replace)), encoded, data]
        self._size += len(encoded) + len(data) + _HEADER.size
        if self._size >= _BATCH:
            self._flush()

    def checkpoint(self) -> int:
        """Mark everything written so far; :meth:`wait` with the number returned waits until it is on disk."""
        self._checkpoints += 1
        if self._pid:
            self._pending.append(_HEADER.pack(0, 0, 0))
            self._flush()
        else:
            self._confirmed = self._checkpoints
        return self._checkpoints

    def wait(self, checkpoint: int) -> None:
        """Block until every file written before ``checkpoint`` is on disk; raises the child's :class:`OSError`."""
        while self._confirmed < checkpoint:
            if not self._pid:
                raise self._error or OSError("the file writer process ended early")
            answer = os.read(self._acks, 1)
            if answer == b"+":
                self._confirmed += 1
            else:
                self._finish(answer)  # raises the child's error, or the child ended early
                if self._confirmed < checkpoint:
                    raise OSError("the file writer process ended early")

    def _flush(self) -> None:
        if not self._pending:
            return
        data = b"".join(self._pending)
        self._pending, self._size = [], 0
        try:
            _write_all(self._pipe, data)
        except BrokenPipeError:
            self._finish(os.read(self._acks, 1))  # raises the child's error
            raise

    def close(self) -> None:
        """Wait until every file is written; raises :class:`OSError` if one could not be."""
        if self._pid:
            self.wait(self.checkpoint())
            self._finish(b"")

    def _finish(self, first: bytes) -> None:
        """End the child (closing its input), count its last acknowledgements, raise the error it reported."""
        if not self._pid:
            if self._error is not None:
                raise self._error
            return
        os.close(self._pipe)
        chunks = [first]
        while chunk := os.read(self._acks, 65536):
            chunks.append(chunk)
        answers = b"".join(chunks)
        report = answers.lstrip(b"+")
        self._confirmed += len(answers) - len(report)
        _pid, status = os.waitpid(self._pid, 0)
        self._pid = 0
        os.close(self._acks)
        if report or os.waitstatus_to_exitcode(status) != 0:
            self._error = _child_error(report[1:], status)
            raise self._error

    def __enter__(self) -> FileWriter:
        return self

    def end_quietly(self) -> None:
        """Let the child write what it was sent and end, ignoring its error: another one is on its way already."""
        try:
            self.close()
        except OSError:
            pass

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 traceback: TracebackType | None) -> None:
        if exc_type is None:
            self.close()
        else:
            self.end_quietly()


def _child_error(payload: bytes, status: int) -> OSError:
    """The :class:`OSError` the child reported (``payload``), or one saying how it ended."""
    try:
        report = json.loads(payload.decode("utf-8", "replace"))
    except ValueError:
        return OSError(f"the file writer process failed (exit status {os.waitstatus_to_exitcode(status)})")
    if report.get("errno") is not None:
        return OSError(report["errno"], report.get("strerror") or report.get("text"), report.get("filename"))
    return OSError(report.get("text") or "the file writer process failed")


def _widen(pipe: int) -> None:
    """Let ``pipe`` hold a whole batch (Linux; 64 KiB otherwise), so the parent hands a batch over and
    renders the next one while the child writes, instead of waiting for the child to read it."""
    try:
        import fcntl

        fcntl.fcntl(pipe, fcntl.F_SETPIPE_SZ, _BATCH)
    except (ImportError, AttributeError, OSError):  # another system, or a lower pipe-max-size
        pass


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def _serve(fd: int, acks: int) -> None:  # pragma: no cover - runs in the child
    """Read records from ``fd`` until end of file and write them; answer each checkpoint on ``acks``."""
    buffer = bytearray()
    position = 0
    while True:
        chunk = os.read(fd, _BATCH)
        if not chunk:
            break
        buffer += chunk
        while len(buffer) - position >= _HEADER.size:
            path_len, data_len, replace = _HEADER.unpack_from(buffer, position)
            end = position + _HEADER.size + path_len + data_len
            if len(buffer) < end:
                break
            start = position + _HEADER.size
            if path_len:
                path = bytes(buffer[start:start + path_len]).decode("utf-8", "surrogateescape")
                write_file(path, bytes(buffer[start + path_len:end]), bool(replace))
            else:
                _write_all(acks, b"+")
            position = end
        if position:
            del buffer[:position]
            position = 0
