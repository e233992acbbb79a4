"""The worker loop's inbox: events from job threads and the fork server's replies, waited for together.

The loop waits in one ``poll`` on a wake-up pipe, the fork server's socket and the launched
children's process descriptors. A job thread (a job with ``--post-run`` hooks or an echoed output)
puts its event here and writes a byte to the pipe; the server's replies are read by the loop itself
(:meth:`ForkServer.poll <executor.batch.builtin_runner.ForkServer.poll>`), as are the children's
ends, so a job's start and end cross no thread.
Measured with trivial jobs at -j 2: a reader thread handing each reply over through a queue kept two
threads taking the interpreter lock from each other at every system call of the loop (futex waits
and context switches were a fifth of the batch process's CPU).
"""

from __future__ import annotations

import os
import select
import threading
from collections import deque
from collections.abc import Callable, Mapping
from typing import Generic, TypeVar

Event = TypeVar("Event")


class Inbox(Generic[Event]):
    """Events in arrival order; :meth:`wait` returns when one is there, a watched socket is readable, or time is up."""

    def __init__(self) -> None:
        self._items: deque[Event] = deque()
        self._owner = threading.get_ident()
        self._wake_read, self._wake_write = os.pipe2(os.O_NONBLOCK | os.O_CLOEXEC)
        self._woken = False
        self._closed = False

    def put(self, event: Event) -> None:
        """Add an event (from any thread); the loop wakes if it waits."""
        self._items.append(event)
        if threading.get_ident() != self._owner and not self._woken and not self._closed:
            self._woken = True
            try:
                os.write(self._wake_write, b"!")
            except OSError:
                pass                          # full: the loop wakes all the same (closed: nobody waits)

    def take(self) -> list[Event]:
        """Every event there is now (oldest first), leaving none."""
        taken = []
        while self._items:
            taken.append(self._items.popleft())
        return taken

    def wait(self, timeout: float, watched: Mapping[int, Callable[[], object]] | None = None) -> None:
        """Wait up to ``timeout`` seconds for an event, or for a watched descriptor to become readable;
        then call the readable ones' functions (which read them, and may put events). ``poll``, not
        ``select``: descriptors above 1023 (thousands of children at once) are watched as well."""
        if self._items:
            timeout = 0.0
        poller = select.poll()
        poller.register(self._wake_read, select.POLLIN)
        for fd in watched or ():
            poller.register(fd, select.POLLIN)
        for fd, _mask in poller.poll(timeout * 1000.0):
            if fd == self._wake_read:
                try:
                    while os.read(self._wake_read, 4096):
                        pass
                except BlockingIOError:
                    pass
                self._woken = False           # after the drain: a later put writes again
            elif watched is not None:
                watched[fd]()

    def close(self) -> None:
        self._closed = True
        for fd in (self._wake_read, self._wake_write):
            try:
                os.close(fd)
            except OSError:
                pass
