"""Local controller: follow the planned path with a differential-drive robot, then turn to the goal's heading.

A pure-pursuit follower: it steers towards the path point ``lookahead`` metres ahead of the
closest one, turns in place when that point is far off its heading, slows down near the goal,
and when within ``xy_goal_tolerance`` of the goal turns in place until within
``yaw_goal_tolerance`` of the goal's yaw (the goal checker then reports success, as Nav2's
``SimpleGoalChecker`` does, keeping "position reached" once it was reached).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from executor.simulations.navigation.localization import wrap


@dataclass
class FollowerSettings:
    """Parameters of the follower and goal checker (Nav2-like names and defaults)."""

    desired_linear_vel: float = 0.5      # m/s
    max_angular_vel: float = 1.0         # rad/s
    lookahead: float = 0.6               # m
    rotate_to_heading_min_angle: float = 0.785  # rad: turn in place above this heading error
    xy_goal_tolerance: float = 0.25      # m
    yaw_goal_tolerance: float = 0.25     # rad


class PathFollower:
    """Velocity commands ``(v, w)`` along a path; see the module docstring."""

    def __init__(self, settings: FollowerSettings) -> None:
        self.settings = settings
        self.path: list[tuple[float, float]] = []
        self.goal = (0.0, 0.0, 0.0)
        self._index = 0
        self.position_reached = False

    def set_goal(self, goal: tuple[float, float, float]) -> None:
        self.goal = goal
        self.position_reached = False
        self.path = []
        self._index = 0

    def set_path(self, path: list[tuple[float, float]]) -> None:
        self.path = path
        self._index = 0

    def remaining(self, pose: tuple[float, float, float], ahead: float) -> list[tuple[float, float]]:
        """The path points from the closest one up to ``ahead`` metres further."""
        self._advance(pose)
        points, travelled, previous = [], 0.0, (pose[0], pose[1])
        for point in self.path[self._index:]:
            travelled += math.hypot(point[0] - previous[0], point[1] - previous[1])
            if travelled > ahead:
                break
            points.append(point)
            previous = point
        return points

    def goal_reached(self, pose: tuple[float, float, float]) -> bool:
        s = self.settings
        gx, gy, gyaw = self.goal
        if math.hypot(gx - pose[0], gy - pose[1]) <= s.xy_goal_tolerance:
            self.position_reached = True
        return self.position_reached and abs(wrap(gyaw - pose[2])) <= s.yaw_goal_tolerance

    def command(self, pose: tuple[float, float, float]) -> tuple[float, float]:
        """``(linear m/s, angular rad/s)`` for the robot at ``pose``."""
        s = self.settings
        x, y, yaw = pose
        gx, gy, gyaw = self.goal
        if self.position_reached or math.hypot(gx - x, gy - y) <= s.xy_goal_tolerance:
            self.position_reached = True
            return 0.0, self._turn(wrap(gyaw - yaw))
        if not self.path:
            return 0.0, 0.0
        tx, ty = self._target(pose)
        error = wrap(math.atan2(ty - y, tx - x) - yaw)
        if abs(error) > s.rotate_to_heading_min_angle:
            return 0.0, self._turn(error)
        distance = math.hypot(gx - x, gy - y)
        speed = s.desired_linear_vel * max(0.2, 1.0 - abs(error) / (1.5 * s.rotate_to_heading_min_angle))
        speed = min(speed, max(0.1, 0.8 * distance))
        curvature = 2.0 * math.sin(error) / max(math.hypot(tx - x, ty - y), 1e-3)
        angular = max(-s.max_angular_vel, min(s.max_angular_vel, speed * curvature))
        return speed, angular

    def _turn(self, error: float) -> float:
        s = self.settings
        rate = 1.5 * error
        if abs(rate) < 0.3:
            rate = math.copysign(0.3, error)
        return max(-s.max_angular_vel, min(s.max_angular_vel, rate))

    def _advance(self, pose: tuple[float, float, float]) -> None:
        """Move the closest-point index forward (never backwards) along the path."""
        x, y, _ = pose
        best, best_distance = self._index, math.inf
        for i in range(self._index, min(len(self.path), self._index + 40)):
            px, py = self.path[i]
            d = math.hypot(px - x, py - y)
            if d < best_distance:
                best, best_distance = i, d
        self._index = best

    def _target(self, pose: tuple[float, float, float]) -> tuple[float, float]:
        self._advance(pose)
        x, y, _ = pose
        for point in self.path[self._index:]:
            if math.hypot(point[0] - x, point[1] - y) >= self.settings.lookahead:
                return point
        return self.path[-1]
