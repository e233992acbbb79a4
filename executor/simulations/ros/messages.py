"""The ``msg_conversion`` external methods of ``osc.ros``: they convert ROS messages, so they need ROS."""

from __future__ import annotations

from typing import NoReturn


def _needs_ros(name: str) -> NoReturn:
    raise RuntimeError(f"msg_conversion.{name}() converts ROS messages and needs ROS")


def get_object_member(in_value: object, member_name: str = "") -> NoReturn:
    _needs_ros("get_object_member")


def to_pose_3d(in_value: object) -> NoReturn:
    _needs_ros("to_pose_3d")
