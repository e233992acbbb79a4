"""The ``osc.nav2`` actions on the PyBullet navigation backend.

``init_nav2`` starts the robot's navigation (spawning the robot if needed); ``nav_to_pose`` and
``nav_through_poses`` send a goal and follow it to its end: success when the robot is within the
goal tolerances, failure when the goal is aborted (no path, no progress). A goal still running
when its action is stopped (a ``timeout``, the end of a ``parallel``) is canceled.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import py_trees

from executor.actions.base import ActionError
from executor.simulations.navigation.planner import path_length
from executor.simulations.navigation.stack import SUCCEEDED, Goal, RobotStack
from executor.simulations.pybullet.access import WorldAction
from executor.simulations.pybullet.navigation import NavigationWorld

Status = py_trees.common.Status


def pose_2d(pose: Mapping[str, Any]) -> tuple[float, float, float]:
    """``(x, y, yaw)`` of a ``pose_3d`` value."""
    return float(pose["position"]["x"]), float(pose["position"]["y"]), float(pose["orientation"]["yaw"])


def namespace_of(actor: Mapping[str, Any] | None, override: str) -> str:
    """The robot's ROS namespace: the action's override, else the actor's ``namespace``, without slashes."""
    return str(override or (actor or {}).get("namespace") or "").strip("/")


class InitNav2(WorldAction):
    """``robot.init_nav2(initial_pose, ...)``: bring up navigation, localised at ``initial_pose``.

    With ``use_initial_pose: false`` the robot maps as it drives (SLAM: no prior map, the costmap
    is what the laser has seen, the pose comes from odometry).
    """

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.actor = associated_actor or {}
        self.arguments: dict[str, Any] = {}

    def execute(self, initial_pose: dict[str, Any], base_frame_id: str = "base_link", use_initial_pose: bool = True,
                namespace_override: str = "", wait_for_initial_pose: bool = False, wait_for_amcl: bool = True) -> None:
        """``wait_for_amcl`` is accepted: the simulated localisation is ready as soon as navigation is up."""
        self.arguments = {"initial_pose": initial_pose, "use_initial_pose": use_initial_pose,
                          "namespace": namespace_of(self.actor, namespace_override),
                          "wait_for_initial_pose": wait_for_initial_pose}

    def update(self) -> Status:
        self.lease.catch_up()
        if self.arguments["wait_for_initial_pose"]:
            raise ActionError("wait_for_initial_pose: the initial pose would be set from outside "
                              "(e.g. RViz), which needs ROS; give initial_pose instead")
        navigation = NavigationWorld.of(self.lease)
        initial = pose_2d(self.arguments["initial_pose"])
        stack = navigation.start_navigation(self.actor_name, initial, self.arguments["use_initial_pose"],
                                            self.arguments["namespace"])
        self.feedback_message = f"navigation up ({stack.mode}) at {initial[0]:.2f}, {initial[1]:.2f}"
        self.logger.info(self.feedback_message)
        return Status.SUCCESS


class _Navigate(WorldAction):
    """Send a goal of one or more poses and wait for its end."""

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.poses: list[tuple[float, float, float]] = []
        self.success_on_acceptance = False
        self.goal: Goal | None = None
        self.stack: RobotStack | None = None

    def update(self) -> Status:
        self.lease.catch_up()
        goal, stack = self.goal, self.stack
        if goal is None or stack is None:
            stack = self.stack = NavigationWorld.of(self.lease).stack(self.actor_name)
            goal = self.goal = stack.start(self.poses, self.world.time)
            target = self.poses[-1]
            self.logger.info(f"goal accepted: ({target[0]:.2f}, {target[1]:.2f}, yaw {target[2]:.2f})"
                             + (f" through {len(self.poses)} poses" if len(self.poses) > 1 else ""))
            if self.success_on_acceptance:
                return Status.SUCCESS
        if goal.status == SUCCEEDED:
            self.logger.info(self._summary(goal, "goal reached"))
            return Status.SUCCESS
        if goal.done:
            self.feedback_message = f"goal {goal.status}: {goal.message}"
            self.logger.error(self._summary(goal, f"goal {goal.status}: {goal.message}"))
            return Status.FAILURE
        x, y, _ = stack.pose
        target = goal.poses[goal.index]
        self.feedback_message = (f"pose {goal.index + 1}/{len(goal.poses)}: "
                                 f"{math.hypot(target[0] - x, target[1] - y):.2f} m to go")
        return Status.RUNNING

    def _summary(self, goal: Goal, what: str) -> str:
        start = goal.trail[0] if goal.trail else (0.0, 0.0)
        straight = path_length([start, *[(p[0], p[1]) for p in goal.poses]])
        elapsed = (goal.finished_at or self.world.time) - goal.accepted_at
        return (f"{what} after {elapsed:.2f} s: driven {path_length(goal.trail):.2f} m "
                f"(straight line {straight:.2f} m)")

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID and self.goal is not None and not self.goal.done and self.stack is not None:
            self.stack.cancel(self.world.time)
        if new_status == Status.INVALID:
            self.goal = None


class NavToPose(_Navigate):
    """``robot.nav_to_pose(goal_pose, ...)``."""

    def execute(self, goal_pose: dict[str, Any], namespace_override: str = "", action_topic: str = "navigate_to_pose",
                success_on_acceptance: bool = False) -> None:
        self.poses = [pose_2d(goal_pose)]
        self.success_on_acceptance = success_on_acceptance
        self.goal = None


class NavThroughPoses(_Navigate):
    """``robot.nav_through_poses(goal_poses, ...)``."""

    def execute(self, goal_poses: list, namespace_override: str = "",
                action_topic: str = "navigate_through_poses", success_on_acceptance: bool = False) -> None:
        if not goal_poses:
            raise ActionError("goal_poses is empty")
        self.poses = [pose_2d(p) for p in goal_poses]
        self.success_on_acceptance = success_on_acceptance
        self.goal = None


class FollowWaypoints(_Navigate):
    """``robot.follow_waypoints(goal_poses, loop_count, ...)``: through the poses, ``loop_count`` more times again."""

    def execute(self, goal_poses: list, loop_count: int = 0, namespace_override: str = "",
                action_topic: str = "follow_waypoints", success_on_acceptance: bool = False) -> None:
        if not goal_poses:
            raise ActionError("goal_poses is empty")
        if loop_count < 0:
            raise ActionError(f"loop_count is {loop_count}: it counts the extra rounds, 0 or more")
        self.poses = [pose_2d(p) for p in goal_poses] * (loop_count + 1)
        self.success_on_acceptance = success_on_acceptance
        self.goal = None
