"""When the worker may talk to the store and claim: back-off while the store is unreachable, polling when idle.

Two small state holders the worker loop asks before each step. :class:`StoreBackoff` runs a store
step and, when the store cannot be reached, says so once and holds every step back for a while
(0.5 s doubling to 30 s); results wait in memory meanwhile. :class:`ClaimPacer` says when to claim:
at once while the last claim filled every free slot, else after the poll interval (an empty queue
is asked again only every ``poll`` seconds).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TypeVar

from store.queue import StoreUnavailable

T = TypeVar("T")

#: The first wait after the store could not be reached, and the longest.
FIRST_BACKOFF = 0.5
LONGEST_BACKOFF = 30.0


class StoreBackoff:
    """Runs store steps; while the store is unreachable, steps wait (doubling) and it is said once."""

    def __init__(self, warn: Callable[[str], None], clock: Callable[[], float] = time.monotonic) -> None:
        self._warn = warn
        self._clock = clock
        self._backoff = 0.0
        self._warned = False
        #: No store step before this time (``time.monotonic``).
        self.retry_at = 0.0

    def ready(self, now: float) -> bool:
        """Whether a store step may run now (no back-off under way)."""
        return now >= self.retry_at

    def run(self, step: Callable[[], T]) -> tuple[bool, T | None]:
        """``(True, value)`` of ``step()``; ``(False, None)`` when the store was unreachable (back-off starts)."""
        try:
            value = step()
        except StoreUnavailable as exc:
            self._backoff = min(LONGEST_BACKOFF, max(FIRST_BACKOFF, self._backoff * 2))
            self.retry_at = self._clock() + self._backoff
            if not self._warned:
                self._warn(f"{exc}; retrying (results are kept until written)")
                self._warned = True
            return False, None
        if self._backoff:
            self._backoff = 0.0
            self._warned = False
        return True, value


class ClaimPacer:
    """Claim again at once while claims fill every free slot; after ``poll`` seconds once one did not."""

    def __init__(self, poll: float, clock: Callable[[], float] = time.monotonic) -> None:
        self.poll = poll
        self._clock = clock
        self._eager = True            # the last claim got all it asked for: more may be waiting
        self._next = 0.0

    @property
    def eager(self) -> bool:
        """Whether the queue may hold more jobs right now (claim without waiting for the poll)."""
        return self._eager

    def due(self, now: float) -> bool:
        return self._eager or now >= self._next

    def claimed(self, asked: int, got: int) -> None:
        """A claim asked for ``asked`` jobs and got ``got``: fewer means the queue is empty for now."""
        self._eager = got == asked
        if not self._eager:
            self._next = self._clock() + self.poll

    def wake(self) -> None:
        """Jobs came back to the queue (a retry, a reclaim): claim at once."""
        self._eager = True

    def idle(self) -> None:
        """Claim no more until the poll interval says so (a halted batch)."""
        self._eager = False
        self._next = self._clock() + self.poll
