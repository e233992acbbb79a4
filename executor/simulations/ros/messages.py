"""The ``msg_conversion`` external methods of ``osc.ros``: they convert ROS messages, so they need ROS."""

from __future__ import annotations


def _needs_ros(name: str):
    raise RuntimeError(f"msg_conversion.{name}() converts ROS messages and needs ROS")


def get_object_member(in_value, member_name=""):
    _needs_ros("get_object_member")


def to_pose_3d(in_value):
    _needs_ros("to_pose_3d")
