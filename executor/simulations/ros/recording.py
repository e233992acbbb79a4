"""``bag_record``: record simulated topics for the rest of the scenario, as JSON lines.

The folder is ``<output_dir>/rosbag2`` (``rosbag2_<YYYY_MM_DD-HH_MM_SS>`` with
``timestamp_suffix``, the timestamp being the wall-clock start, as ``ros2 bag record`` names it);
``messages.jsonl`` in it has one ``{"t": simulated s, "topic": ..., "message": {...}}`` per line,
and ``metadata.json`` the requested and the recorded topics. Lines are flushed once per simulated
second and when the scenario ends, so a crash loses at most the last second. Topics the
simulation does not produce are named in the log and in the metadata.
"""

from __future__ import annotations

import datetime
import json
import os
from pathlib import Path
from typing import Any, TextIO

import py_trees

from executor.actions.base import ActionError
from executor.simulations.pybullet.access import WorldAction
from executor.simulations.pybullet.navigation import NavigationWorld

Status = py_trees.common.Status

#: the topics the navigation backend publishes (per robot, under its namespace)
SIMULATED = ("/scan", "/odom", "/cmd_vel", "/tf", "/robot_pose_gt", "/robot_pose_loc", "/amcl_pose")


class BagRecord(WorldAction):
    """``bag_record(topics, timestamp_suffix, ...)``; see the module docstring."""

    def __init__(self) -> None:
        super().__init__(None)
        self.topics: list[str] = []
        self.timestamp_suffix = True
        self._file: TextIO | None = None
        self._last_flush = 0.0
        self.folder: Path | None = None

    def execute(self, topics: list[object], timestamp_suffix: bool = True, hidden_topics: bool = False,
                storage: str = "", use_sim_time: bool = False) -> None:
        self.topics = [str(t) for t in topics]
        self.timestamp_suffix = timestamp_suffix

    def update(self) -> Status:
        self.lease.catch_up()
        if self._file is not None:
            return Status.SUCCESS
        output = self.lease.output_dir or os.getcwd()
        name = "rosbag2"
        if self.timestamp_suffix:
            name += datetime.datetime.now().strftime("_%Y_%m_%d-%H_%M_%S")
        self.folder = Path(output) / name
        try:
            self.folder.mkdir(parents=True, exist_ok=False)
        except OSError as exc:
            raise ActionError(f"cannot create the recording folder {self.folder}: {exc}") from None
        simulated = [t for t in self.topics if any(t.endswith(s) for s in SIMULATED)]
        missing = [t for t in self.topics if t not in simulated]
        (self.folder / "metadata.json").write_text(json.dumps(
            {"requested": self.topics, "recorded": simulated if self.topics else list(SIMULATED),
             "not_simulated": missing, "format": "JSON lines: t (simulated s), topic, message"}, indent=2) + "\n",
            encoding="utf-8")
        if missing:
            self.logger.warning(f"not simulated, not recorded: {', '.join(missing)}")
        self._file = open(self.folder / "messages.jsonl", "w", encoding="utf-8")  # noqa: SIM115 - open until shutdown
        navigation = NavigationWorld.of(self.lease)
        navigation.subscribers.append(self._receive)
        self.world.on_close(self._close)
        self.logger.info(f"recording to {self.folder}")
        return Status.SUCCESS

    def _receive(self, now: float, topic: str, message: dict[str, Any]) -> None:
        if self._file is None or (self.topics and topic not in self.topics):
            return
        self._file.write(json.dumps({"t": round(now, 6), "topic": topic, "message": message}) + "\n")
        if now - self._last_flush >= 1.0:
            self._file.flush()
            self._last_flush = now

    def _close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def shutdown(self) -> None:
        self._close()
        super().shutdown()
