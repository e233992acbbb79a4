"""The ``osc.ros`` actions that work on the simulated robot: tf_close_to, odometry_distance_traveled,
set_node_parameter (``bag_record`` is in :mod:`executor.simulations.ros.recording`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import py_trees

from executor.actions.base import ActionError
from executor.simulations.navigation.parameters import ParameterError
from executor.simulations.pybullet.access import WorldAction
from executor.simulations.pybullet.navigation import NavigationWorld

Status = py_trees.common.Status


class TfCloseTo(WorldAction):
    """``robot.tf_close_to(threshold, reference_point, robot_frame_id, ...)``.

    Succeeds once the robot is within ``threshold`` of ``reference_point`` in the x-y plane. A
    ``robot_frame_id`` ending in ``_gt`` (``turtlebot4_base_link_gt``) reads the ground truth, as
    such frames do in simulation; any other frame the localised pose.
    """

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.threshold = 0.0
        self.point = (0.0, 0.0)
        self.ground_truth = False

    def execute(self, threshold: float, reference_point: Mapping[str, Any], robot_frame_id: str = "base_link",
                sim: bool = False, namespace_override: str = "", parent_frame_id: str = "map") -> None:
        self.threshold = threshold
        self.point = (float(reference_point["x"]), float(reference_point["y"]))
        self.ground_truth = robot_frame_id.endswith("_gt")

    def update(self) -> Status:
        self.lease.catch_up()
        navigation = NavigationWorld.of(self.lease)
        if self.ground_truth or self.actor_name not in navigation.robots:
            x, y, _ = navigation.base(self.actor_name).true_pose()
        else:
            x, y, _ = navigation.stack(self.actor_name).pose
        distance = math.hypot(x - self.point[0], y - self.point[1])
        self.feedback_message = f"{distance:.2f} m from ({self.point[0]:.2f}, {self.point[1]:.2f})"
        if distance <= self.threshold:
            self.logger.info(f"within {self.threshold:.2f} m of ({self.point[0]:.2f}, {self.point[1]:.2f})")
            return Status.SUCCESS
        return Status.RUNNING


class OdometryDistanceTraveled(WorldAction):
    """``robot.odometry_distance_traveled(distance)``: succeeds once odometry has covered ``distance``."""

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.distance = 0.0
        self.start: float | None = None

    def execute(self, distance: float, namespace_override: str = "") -> None:
        self.distance = distance
        self.start = None

    def update(self) -> Status:
        self.lease.catch_up()
        navigation = NavigationWorld.of(self.lease)
        if self.actor_name not in navigation.robots:
            raise ActionError(f"robot '{self.actor_name}' has no odometry: call {self.actor_name}.init_nav2(...) first")
        odometry = navigation.stack(self.actor_name).odometry_distance
        if self.start is None:
            self.start = odometry
        traveled = odometry - self.start
        self.feedback_message = f"traveled {traveled:.2f} m of {self.distance:.2f} m"
        return Status.SUCCESS if traveled >= self.distance else Status.RUNNING


class SetNodeParameter(WorldAction):
    """``set_node_parameter(node_name, parameter_name, parameter_value)`` on a simulated node."""

    def __init__(self) -> None:
        super().__init__(None)
        self.request = ("", "", "")

    def execute(self, node_name: str, parameter_name: str, parameter_value: str) -> None:
        self.request = (node_name, parameter_name, parameter_value)

    def update(self) -> Status:
        self.lease.catch_up()
        node, parameter, text = self.request
        try:
            value = NavigationWorld.of(self.lease).nodes.set(node, parameter, text)
        except ParameterError as exc:
            raise ActionError(str(exc)) from None
        self.feedback_message = f"{node}.{parameter} = {value!r}"
        self.logger.info(f"set {self.feedback_message}")
        return Status.SUCCESS
