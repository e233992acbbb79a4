"""What can go wrong between the runner and its fork server, as exceptions the runner's callers tell apart.

:class:`ForkServerError` is any failure to start a job through the server (it is an ``OSError``: a
job's start fails as a launched command's does); :class:`ForkServerEnded` says the server ended before
the job started, so the job may run on the next server; :class:`JobFolderRefused` that the server could
not make the job's folder.
"""

from __future__ import annotations

from errno import ECONNRESET, ENOTCONN, EPIPE


class ForkServerError(OSError):
    """The fork server could not be started, or ended."""


class ForkServerEnded(ForkServerError):
    """The fork server ended before it said the job started: the job did not run (or only for the moment
    between its fork and the server's end, which ended it too), so it may run on the next server."""


#: What a send to a server that has died meanwhile fails with (before its end has been read).
PEER_GONE = frozenset({EPIPE, ECONNRESET, ENOTCONN})


class JobFolderRefused(ForkServerError):
    """The server could not make the job's folder (a full disk, a folder that leads elsewhere)."""


def start_failure(reason: str | None, errno: int | None = None, folder: bool = False) -> ForkServerError:
    """The error of a job the server could not start (its ``failed`` reply, or ``reason`` alone)."""
    if folder:
        return JobFolderRefused(errno, reason)
    message = f"the built-in runner could not start the job: {reason}"
    return ForkServerError(message) if errno is None else ForkServerError(errno, message)
