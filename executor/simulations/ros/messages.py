"""The external methods of ``osc.ros`` (``msg_conversion``, ``ament``): they read ROS messages or a ROS
installation, so they fail naming ROS."""

from __future__ import annotations

from typing import NoReturn


def _needs_ros(name: str) -> NoReturn:
    raise RuntimeError(f"msg_conversion.{name}() converts ROS messages and needs ROS")


def get_object_member(in_value: object, member_name: str = "") -> NoReturn:
    _needs_ros("get_object_member")


def to_pose_3d(in_value: object) -> NoReturn:
    _needs_ros("to_pose_3d")


def get_package_share_directory(package_name: str) -> NoReturn:
    """``ament.get_package_share_directory``: package share folders exist only in a ROS (ament) installation."""
    raise RuntimeError(f"ament.get_package_share_directory('{package_name}') needs ROS: "
                       "no ament installation on this ROS-free backend")
