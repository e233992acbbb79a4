"""Plain line logger for scenario runs: ``[LEVEL] [source] message`` on stdout.

Log lines are for people and for CI logs alike, so they are plain text (no colour, no timestamps
that make outputs differ run to run) and flushed at once, keeping their order with the output of
child processes and hooks. ``debug`` is a cheap no-op unless enabled, because py_trees calls it for
every behaviour on every tick.
"""

from __future__ import annotations

import sys
import threading
from typing import TextIO

_lock = threading.Lock()


class Logger:
    """A named logger; :meth:`child` makes one for an action (``[hello/log] …``)."""

    __slots__ = ("name", "debug_enabled", "stream")

    def __init__(self, name: str = "scenario_execution", debug: bool = False, stream: TextIO | None = None) -> None:
        self.name = name
        self.debug_enabled = debug
        self.stream = stream

    def child(self, name: str) -> Logger:
        return Logger(name, self.debug_enabled, self.stream)

    def _emit(self, level: str, msg: object) -> None:
        stream = self.stream or sys.stdout
        text = f"[{level}] [{self.name}] {msg}\n"
        with _lock:
            stream.write(text)
            stream.flush()

    def info(self, msg: object) -> None:
        self._emit("INFO", msg)

    def warning(self, msg: object) -> None:
        self._emit("WARN", msg)

    def error(self, msg: object) -> None:
        self._emit("ERROR", msg)

    def debug(self, msg: object) -> None:
        if self.debug_enabled:
            self._emit("DEBUG", msg)
