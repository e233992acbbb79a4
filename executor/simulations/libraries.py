"""Entry points of group ``scenario_execution.osc_libraries`` for the simulation libraries.

Each returns ``(package, file name)``; the file is ``<package>/lib_osc/<file name>``. This module
imports nothing, so resolving ``import osc.pybullet`` (also with ``-n``) never loads an engine.
"""

from __future__ import annotations


def get_pybullet_library() -> tuple[str, str]:
    """``import osc.pybullet``: the PyBullet world and bodies."""
    return "executor.simulations.pybullet", "pybullet.osc"


def get_ros_library() -> tuple[str, str]:
    """``import osc.ros``: the ROS library's declarations; the robot actions run on PyBullet."""
    return "executor.simulations.ros", "ros.osc"


def get_nav2_library() -> tuple[str, str]:
    """``import osc.nav2``: navigation actions, on the PyBullet navigation backend."""
    return "executor.simulations.nav2", "nav2.osc"


def get_gazebo_library() -> tuple[str, str]:
    """``import osc.gazebo``: spawn and delete entities, on the PyBullet world."""
    return "executor.simulations.gazebo", "gazebo.osc"
