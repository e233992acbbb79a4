"""``--bt-log`` and ``--tick-log``: what the behaviour tree did over time, written beside ``test.xml``.

Both follow the reference's 1.8.0 options of the same names, so tools written for its files read ours:

* ``behaviors.jsonl`` (``--bt-log``): one JSON object per line. The first line says what ran (``format``,
  ``version``, scenario, file and its SHA-256, tick period, clock); then every behaviour of the tree once at
  timestamp 0 with status ``INVALID`` (so the file alone gives the tree's shape, branches that never ran
  included); then one line each time a behaviour's status changes after a tick.
* ``tick_timing.csv`` (``--tick-log``): one row per tick: the interval since the previous tick, how long the
  tick took and the period it aimed at; ``action_timing.csv``: one row per ``setup``, ``initialise`` and
  ``update`` call of a leaf, so a slow tick can be put down to the action that spent the time.

Timestamps are seconds on the scenario's clock (simulated time with ``--simulation``, else monotonic time
since the scenario started); ``wall_ts`` is the host's time. The files are streams, not results: each line is
written and flushed as it happens, straight into the final name (opened without following a link), so a
scenario that is killed leaves every line up to that moment. Nothing is installed unless an option asks.
"""

from __future__ import annotations

import csv
import hashlib
import json
import os
import time
from collections.abc import Callable
from datetime import datetime, timezone
from typing import IO, Any

import py_trees
from py_trees.behaviour import Behaviour

from executor.runtime.simulation import Clock, SimulationClock

BEHAVIOUR_LOG = "behaviors.jsonl"
TICK_TIMING = "tick_timing.csv"
ACTION_TIMING = "action_timing.csv"
#: The behaviour methods whose calls ``action_timing.csv`` times.
TIMED_PHASES = ("setup", "initialise", "update")

_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)


def open_stream(folder: str, name: str) -> IO[str]:
    """``folder/name`` for writing line by line (replaced if it is there; a link there is refused)."""
    fd = os.open(os.path.join(folder, name), _FLAGS, 0o644)
    return os.fdopen(fd, "w", encoding="utf-8", newline="")


def _kind(node: Behaviour) -> str:
    """``SEQUENCE``, ``SELECTOR``, ``PARALLEL``, ``DECORATOR`` or ``BEHAVIOUR``, as py_trees names its types."""
    for cls, name in ((py_trees.composites.Sequence, "SEQUENCE"), (py_trees.composites.Selector, "SELECTOR"),
                      (py_trees.composites.Parallel, "PARALLEL"), (py_trees.decorators.Decorator, "DECORATOR")):
        if isinstance(node, cls):
            return name
    return "BEHAVIOUR"


def _class_name(node: Behaviour) -> str:
    return f"{type(node).__module__}.{type(node).__qualname__}"


def _version(distribution: str) -> str | None:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(distribution)
    except PackageNotFoundError:
        return None


def _file_digest(path: str | None) -> str | None:
    if not path:
        return None
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as handle:
            for block in iter(lambda: handle.read(1 << 16), b""):
                digest.update(block)
    except OSError:
        return None
    return digest.hexdigest()


class BehaviourLog:
    """``behaviors.jsonl``: the tree once, then every change of a behaviour's status."""

    def __init__(self, folder: str, clock: Clock, scenario: str, scenario_file: str | None,
                 tick_period: float) -> None:
        self.clock = clock
        self.stream = open_stream(folder, BEHAVIOUR_LOG)
        self.last: dict[Any, str] = {}
        meta = {"format": "behavior_tree_log", "version": 1, "scenario": scenario, "scenario_file": scenario_file,
                "scenario_sha256": _file_digest(scenario_file), "tick_period": tick_period,
                "clock": "SimulationClock" if isinstance(clock, SimulationClock) else "monotonic",
                "py_trees": _version("py_trees"),
                "started_at": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")}
        self._write(meta)

    def _write(self, record: dict[str, Any]) -> None:
        self.stream.write(json.dumps(record, separators=(",", ":")) + "\n")
        self.stream.flush()

    def _record(self, node: Behaviour, timestamp: float, active: bool) -> dict[str, Any]:
        parent = node.parent
        location = getattr(node, "osc_location", None)
        tip = node.tip() if node.children else None
        return {"timestamp": timestamp, "behavior_id": str(node.id),
                "parent_id": str(parent.id) if parent is not None else None,
                "child_index": parent.children.index(node) if parent is not None else None,
                "behavior_name": node.name, "class_name": _class_name(node), "type": _kind(node),
                "additional_detail": "", "status": node.status.name, "feedback_message": node.feedback_message,
                "is_active": active, "tip_id": str(tip.id) if tip is not None else None,
                "osc_file": getattr(location, "file", None), "osc_line": getattr(location, "line", None),
                "osc_column": getattr(location, "column", 1) - 1 if location is not None else None}

    def started(self, root: Behaviour) -> None:
        """Every behaviour at timestamp 0 (status ``INVALID``: nothing has run yet)."""
        for node in root.iterate():
            self.last[node.id] = node.status.name
            self._write(self._record(node, 0.0, False))

    def before_tick(self) -> None:
        """Nothing to do before a tick."""

    def after_tick(self, root: Behaviour) -> None:
        """A line for each behaviour whose status the tick changed."""
        now = self.clock.now()
        for node in root.iterate():
            status = node.status.name
            if self.last.get(node.id) != status:
                self.last[node.id] = status
                self._write(self._record(node, now, True))

    def close(self) -> None:
        self.stream.close()


class TickTiming:
    """``tick_timing.csv`` and ``action_timing.csv``: how long ticks and action calls took."""

    def __init__(self, folder: str, clock: Clock, tick_period: float, driver: str) -> None:
        self.clock, self.period, self.driver = clock, tick_period, driver
        self.ticks_stream = open_stream(folder, TICK_TIMING)
        self.actions_stream = open_stream(folder, ACTION_TIMING)
        self.ticks = csv.writer(self.ticks_stream, lineterminator="\n")
        self.actions = csv.writer(self.actions_stream, lineterminator="\n")
        self.ticks.writerow(["tick", "wall_ts", "timestamp", "interval_s", "duration_s", "period_s", "driver"])
        self.actions.writerow(["tick", "wall_ts", "timestamp", "behavior_id", "behavior_name", "class_name",
                               "phase", "duration_s", "status"])
        self.tick = 0                         # 0 while the tree is set up, then the number of the running tick
        self.tick_started = 0.0
        self.previous_start: float | None = None

    def started(self, root: Behaviour) -> None:
        """Time every leaf's setup, initialise and update from now on (the tree is not set up yet)."""
        for node in root.iterate():
            if not node.children:
                for phase in TIMED_PHASES:
                    setattr(node, phase, self._timed(node, phase, getattr(node, phase)))

    def _timed(self, node: Behaviour, phase: str, call: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any, **kwargs: Any) -> Any:
            began = time.monotonic()
            returned = None
            try:
                returned = call(*args, **kwargs)
                return returned
            finally:
                # update() returns the status py_trees sets only after it: the row shows the returned one
                status = returned if isinstance(returned, py_trees.common.Status) else node.status
                self.actions.writerow([self.tick or "", f"{time.time():.6f}", f"{self.clock.now():.6f}", node.id,
                                       node.name, _class_name(node), phase, f"{time.monotonic() - began:.6f}",
                                       status.name])
        return timed

    def before_tick(self) -> None:
        self.tick += 1
        self.tick_started = time.monotonic()

    def after_tick(self, root: Behaviour) -> None:
        """One row for the tick just ended; both files are flushed, so a kill loses no finished tick."""
        ended = time.monotonic()
        interval = "" if self.previous_start is None else f"{self.tick_started - self.previous_start:.6f}"
        self.previous_start = self.tick_started
        self.ticks.writerow([self.tick, f"{time.time():.6f}", f"{self.clock.now():.6f}", interval,
                             f"{ended - self.tick_started:.6f}", f"{self.period:.6f}", self.driver])
        self.ticks_stream.flush()
        self.actions_stream.flush()

    def close(self) -> None:
        self.ticks_stream.close()
        self.actions_stream.close()


Recorder = BehaviourLog | TickTiming


def recorders(folder: str | None, clock: Clock, scenario: str, scenario_file: str | None, tick_period: float,
              bt_log: bool, tick_log: bool) -> list[Recorder]:
    """The recorders the options ask for, writing into ``folder`` (the scenario's output folder)."""
    if folder is None:
        return []
    found: list[Recorder] = []
    try:
        if bt_log:
            found.append(BehaviourLog(folder, clock, scenario, scenario_file, tick_period))
        if tick_log:
            driver = "simulation_step" if isinstance(clock, SimulationClock) else "wall_loop"
            found.append(TickTiming(folder, clock, tick_period, driver))
    except OSError:
        for recorder in found:          # the one opened before the failure
            recorder.close()
        raise
    return found
