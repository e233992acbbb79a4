"""The messages between the built-in runner and its fork server, and what the server is to run.

One JSON message per ``sendmsg`` on a Unix socket pair (``SOCK_SEQPACKET``), file descriptors
attached where a request carries the job's output (see :mod:`executor.batch.fork_server` for the
conversation). Standard library only: the server imports this before anything else.
"""

from __future__ import annotations

import array
import json
import os
import socket

#: Largest request or reply, in bytes.
MAX_MESSAGE = 64 * 1024

#: What the runner asks the server to run: the console script of the command (name, group).
ENTRY_POINT = ("scenario_execution", "console_scripts")


def command_target() -> str:
    """Where the console script ``scenario_execution`` points (``module:function``), looked up in the
    runner: the lookup (``importlib.metadata``) imports ``email``, ``zipfile``, ``csv``, ``calendar`` and
    more, which a launched ``scenario_execution`` never loads. Had the server loaded them, a job's
    own ``calendar.py`` beside its scenario would lose to the server's copy and the job differ from
    the launched command."""
    from importlib.metadata import entry_points

    name, group = ENTRY_POINT
    found = [ep for ep in entry_points(group=group) if ep.name == name]
    if not found:
        raise RuntimeError(f"the console script {name!r} is not installed")
    return found[0].value


class FolderRefused(OSError):
    """The job's folder could not be made, or leads out of the output root (see :mod:`executor.batch.job_folders`)."""


def open_log(request: dict) -> int:
    """The job's log, opened (created, or appended to) for a request that names it (``log``, ``append``)
    instead of carrying a descriptor: the server opens it just before the job starts, so the runner's
    own process does not pay for creating a file per job (measured on ext4 under load: 0.4-0.6 ms of
    CPU each, the largest single share of the runner's work per job). With ``folder`` (the output root
    and its real path) the log's folder is made first, as the runner would have made it;
    :class:`FolderRefused` when it cannot be."""
    if request.get("folder"):
        from pathlib import Path

        from executor.batch.job_folders import prepare_job_folder

        root, real_root = request["folder"]
        try:
            prepare_job_folder(Path(root), Path(os.path.dirname(request["log"])), real_root)
        except OSError as exc:
            raise FolderRefused(exc.errno, f"{exc.strerror or exc}" + (f": {exc.filename}" if exc.filename
                                                                      else "")) from exc
    flags = os.O_WRONLY | os.O_CREAT | os.O_CLOEXEC | (os.O_APPEND if request.get("append") else os.O_TRUNC)
    return os.open(request["log"], flags, 0o666)


def fork_paired() -> tuple[int, socket.socket]:
    """Fork, with a socket pair (``SOCK_SEQPACKET``) between parent and child: ``(child's pid, the
    parent's end)`` in the parent, ``(0, the child's end)`` in the child; ``OSError`` when the fork
    fails (both ends closed)."""
    mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    try:
        pid = os.fork()
    except OSError:
        mine.close()
        theirs.close()
        raise
    if pid == 0:
        mine.close()
        return 0, theirs
    theirs.close()
    return pid, mine


def send(sock: socket.socket, message: dict | bytes, fds: list[int] | None = None, flags: int = 0) -> None:
    """One JSON message (or one already encoded), with file descriptors attached when given (``flags``:
    ``socket.MSG_DONTWAIT`` raises :class:`BlockingIOError` instead of waiting for room; a message is
    sent whole or not at all)."""
    data = message if isinstance(message, bytes) else json.dumps(message).encode()
    if fds:
        sock.sendmsg([data], [(socket.SOL_SOCKET, socket.SCM_RIGHTS, array.array("i", fds))], flags)
    else:
        sock.sendmsg([data], [], flags)


def bundles(requests: list[bytes], limit: int = MAX_MESSAGE) -> list[tuple[int, bytes]]:
    """Encoded requests (no descriptors attached) as few messages of at most ``limit`` bytes as can
    hold them, each with the number of requests it carries: ``{"requests": [...]}``, or the request
    itself when it goes alone. One message wakes the server once for all of them (sending each woke
    it each time: measured on 2 cores, a ``sendmsg`` cost the runner 60 us, its reading 4 us). One
    request is far below that size (its paths are bounded by the system's 4 KiB each)."""
    messages: list[tuple[int, bytes]] = []
    group: list[bytes] = []
    size = 0
    for request in requests:
        if group and size + len(request) + 1 > limit - len(_BUNDLE_FRAME):
            messages.append((len(group), _bundle(group)))
            group, size = [], 0
        group.append(request)
        size += len(request) + 1
    if group:
        messages.append((len(group), _bundle(group)))
    return messages


#: What a bundle adds around its requests.
_BUNDLE_FRAME = b'{"requests": []}'


def _bundle(group: list[bytes]) -> bytes:
    return group[0] if len(group) == 1 else b'{"requests": [' + b",".join(group) + b"]}"


def spawn_requests(message: dict, fds: list[int]) -> list[tuple[dict, list[int]]]:
    """The spawn requests of a message the runner sent, each with its descriptors: the requests of a
    bundle (:func:`bundles`, none with a descriptor), or the message itself."""
    if "requests" in message:
        return [(request, []) for request in message["requests"]]
    return [(message, fds)]


def receive(sock: socket.socket, max_fds: int = 0, flags: int = 0, *,
            after_reset: bool = False) -> tuple[dict | None, list[int]]:
    """The next message (None when the other end closed) and the descriptors that came with it
    (``flags``: ``socket.MSG_DONTWAIT`` raises :class:`BlockingIOError` when none is waiting).

    When the other end closed with messages of ours unread, Linux reports a reset to the first read,
    although what it sent before it closed is still queued (the reset is reported once). That is None
    too, unless ``after_reset``: then the queued messages are read on, up to the end. The runner reads
    its server's replies so: a server killed with requests unread had said which jobs it started, and
    a job whose start is lost would outlive it unseen (its process id unknown).
    """
    fds = array.array("i")
    ancillary_size = socket.CMSG_SPACE(max_fds * fds.itemsize) if max_fds else 0
    try:
        data, ancillary, _flags, _addr = sock.recvmsg(MAX_MESSAGE, ancillary_size, flags)
    except ConnectionResetError:
        if not after_reset:
            return None, []
        try:
            data, ancillary, _flags, _addr = sock.recvmsg(MAX_MESSAGE, ancillary_size, flags)
        except (ConnectionResetError, BlockingIOError):
            return None, []
    for level, kind, payload in ancillary:
        if level == socket.SOL_SOCKET and kind == socket.SCM_RIGHTS:
            fds.frombytes(payload[:len(payload) - len(payload) % fds.itemsize])
    if not data:
        for fd in fds:
            os.close(fd)
        return None, []
    return json.loads(data.decode()), list(fds)     # (text: bytes would have their encoding guessed each time)
