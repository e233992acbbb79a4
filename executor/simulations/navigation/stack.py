"""One robot's navigation stack: odometry, scan, localisation, costmap, planner, follower and goals.

The stack is engine-independent: it talks to the robot through a :class:`Base` (ground-truth pose
for the simulation's own use, measured velocity for odometry, velocity commands, ray casting for
the laser) and is called at fixed rates of simulated time by whoever owns the world:
:meth:`RobotStack.sense` (the laser rate) and :meth:`RobotStack.control` (the controller rate).

Goals behave like Nav2's ``NavigateToPose``/``NavigateThroughPoses``: a goal is accepted, the
robot plans on the costmap and follows the path, replans every ``replan_period`` and whenever the
path ahead is blocked, and the goal *succeeds* when the localised pose is within the goal
tolerances. Three things go wrong the way they do in Nav2: no path is found, the controller sees
an obstacle right ahead (a collision), or the robot has not moved ``progress_radius`` within
``progress_timeout``. Each is answered with a recovery (the laser obstacles are cleared from the
costmap, the robot waits ``recovery_wait``, then plans again); after ``recovery_retries``
recoveries (Nav2's ``number_of_retries``) the goal is *aborted*.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from executor.simulations.navigation.controller import FollowerSettings, PathFollower
from executor.simulations.navigation.costmap import Costmap
from executor.simulations.navigation.laser import Laser, ScanModification
from executor.simulations.navigation.localization import DeadReckoning, Localizer, ParticleFilter, wrap
from executor.simulations.navigation.maps import OccupancyMap
from executor.simulations.navigation.planner import path_length, plan

if TYPE_CHECKING:
    from executor.simulations.engines import FloatArray, RandomGenerator

#: ``(x, y, yaw)`` in the map frame
Pose = tuple[float, float, float]


class Base(Protocol):
    """What the stack needs from the robot in the engine."""

    radius: float       # the disk around the centre that must stay free of obstacles
    front: float        # from the centre to the front bumper
    half_width: float

    def true_pose(self) -> tuple[float, float, float]: ...

    def measured_velocity(self) -> tuple[float, float, float]:
        """``(forward m/s, sideways m/s, yaw rate rad/s)`` in the robot's frame, as its odometry reports them."""

    def drive(self, linear: float, angular: float) -> None: ...

    def ray_cast(self, starts: Sequence[Sequence[float]], ends: Sequence[Sequence[float]]) -> list[float]:
        """The hit fraction of each ray (see :data:`~executor.simulations.navigation.laser.RayCast`)."""


ACTIVE, SUCCEEDED, ABORTED, CANCELED = "active", "succeeded", "aborted", "canceled"


@dataclass
class Goal:
    """A navigation request: poses to reach in order; ``status`` moves from active to an end state."""

    poses: list[tuple[float, float, float]]
    status: str = ACTIVE
    message: str = ""
    index: int = 0
    accepted_at: float = 0.0
    finished_at: float | None = None
    path_length_planned: float = 0.0
    recoveries: int = 0
    trail: list[tuple[float, float]] = field(default_factory=list)

    @property
    def done(self) -> bool:
        return self.status != ACTIVE


@dataclass
class StackSettings:
    """Rates, recovery limits and sizes (Nav2-like defaults where Nav2 has them)."""

    control_period: float = 0.05       # 20 Hz controller
    sense_period: float = 0.1          # 10 Hz laser
    replan_period: float = 2.0
    recovery_retries: int = 6
    recovery_wait: float = 1.0
    progress_radius: float = 0.5
    progress_timeout: float = 10.0
    collision_lookahead: float = 0.2   # m ahead of the robot's front checked while driving forward
    inflation_radius: float = 0.8
    odometry_noise: float = 0.02       # relative standard deviation of measured speeds
    follower: FollowerSettings = field(default_factory=FollowerSettings)


class RobotStack:
    """The navigation of one robot; see the module docstring."""

    def __init__(self, name: str, base: Base, grid_map: OccupancyMap, initial: tuple[float, float, float],
                 use_map: bool, seed: int, settings: StackSettings | None = None) -> None:
        from executor.simulations import engines

        self.name = name
        self.base = base
        self.settings = settings = settings or StackSettings()
        self.rng: RandomGenerator = engines.numpy().random.default_rng(seed)
        self.laser = Laser(base.ray_cast)
        self.modification = ScanModification(seed + 1)
        localise_on_map = use_map and grid_map.has_obstacles
        self.localizer: Localizer = (ParticleFilter(grid_map, initial, seed + 2) if localise_on_map
                                     else DeadReckoning(initial))
        self.mode = "amcl" if localise_on_map else ("slam" if not use_map else "odometry")
        self.costmap = Costmap(grid_map, use_static=use_map, robot_radius=base.radius,
                               inflation_radius=settings.inflation_radius)
        self.follower = PathFollower(settings.follower)
        self.odometry_pose: Pose = (0.0, 0.0, 0.0)
        self.odometry_distance = 0.0
        self.last_scan: FloatArray | None = None
        self.last_command: tuple[float, float] = (0.0, 0.0)
        self.goal: Goal | None = None
        self._next_replan = 0.0
        self._recoveries = 0
        self._paused_until = 0.0
        self._progress_anchor = (initial[0], initial[1])
        self._progress_since = 0.0
        self._reached_since: float | None = None
        self.now = 0.0

    # -- what the world calls at fixed rates --------------------------------------------------------

    def sense(self, now: float) -> None:
        """One laser scan: modified by the fault-injection node, then localisation and costmap."""
        self.now = now
        x, y, yaw = self.base.true_pose()
        ranges = self.modification.apply(self.laser.cast(x, y, yaw))
        self.last_scan = ranges
        self.localizer.correct(self.laser.angles, ranges, self.laser.range_max)
        ex, ey, eyaw = self.localizer.pose
        self.costmap.update(ex, ey, eyaw, self.laser.angles, ranges, self.laser.range_min)

    def control(self, now: float) -> None:
        """Odometry, then one controller step towards the active goal."""
        self.now = now
        period = self.settings.control_period
        forward, sideways, turn = self.base.measured_velocity()
        noise = self.settings.odometry_noise
        if noise > 0.0:
            forward, sideways, turn = (v * (1.0 + float(e)) for v, e in
                                       zip((forward, sideways, turn), self.rng.normal(0.0, noise, 3), strict=True))
        delta = (forward * period, sideways * period, turn * period)
        ox, oy, oyaw = self.odometry_pose
        heading = oyaw + delta[2] / 2.0
        c, s = math.cos(heading), math.sin(heading)
        self.odometry_pose = (ox + c * delta[0] - s * delta[1], oy + s * delta[0] + c * delta[1],
                              wrap(oyaw + delta[2]))
        self.odometry_distance += math.hypot(delta[0], delta[1])
        self.localizer.predict(delta)
        self._navigate(now)

    @property
    def pose(self) -> tuple[float, float, float]:
        """The localised pose (map frame)."""
        return self.localizer.pose

    # -- goals ----------------------------------------------------------------------------------

    def start(self, poses: list[tuple[float, float, float]], now: float) -> Goal:
        """Accept a new goal (a running one is canceled, as a new Nav2 goal preempts the old)."""
        if self.goal is not None and not self.goal.done:
            self._finish(self.goal, CANCELED, "preempted by a new goal", now)
        goal = self.goal = Goal(list(poses), accepted_at=now)
        self._recoveries = 0
        self._paused_until = now
        self._begin_pose(goal, now)
        return goal

    def cancel(self, now: float) -> None:
        if self.goal is not None and not self.goal.done:
            self._finish(self.goal, CANCELED, "canceled", now)

    def _begin_pose(self, goal: Goal, now: float) -> None:
        self.follower.set_goal(goal.poses[goal.index])
        self._next_replan = now
        self._progress_anchor = self.pose[:2]
        self._progress_since = now
        self._reached_since = None

    def _finish(self, goal: Goal, status: str, message: str, now: float) -> None:
        goal.status, goal.message, goal.finished_at = status, message, now
        self._drive(0.0, 0.0)

    def _drive(self, linear: float, angular: float) -> None:
        self.last_command = (linear, angular)
        self.base.drive(linear, angular)

    def _navigate(self, now: float) -> None:
        goal = self.goal
        if goal is None or goal.done:
            self._drive(0.0, 0.0)
            return
        pose = self.pose
        true_x, true_y, _ = self.base.true_pose()
        if not goal.trail or math.hypot(true_x - goal.trail[-1][0], true_y - goal.trail[-1][1]) >= 0.05:
            goal.trail.append((true_x, true_y))
        if now < self._paused_until:
            self._drive(0.0, 0.0)
            return
        if self.follower.goal_reached(pose):
            goal.index += 1
            if goal.index >= len(goal.poses):
                self._finish(goal, SUCCEEDED, "goal reached", now)
            else:
                self._begin_pose(goal, now)
                self._drive(0.0, 0.0)
            return
        if not self._plan_if_needed(goal, pose, now) or not self._progressing(goal, pose, now):
            return
        linear, angular = self.follower.command(pose)
        if linear > 0.0 and self._collision_ahead(pose):
            self._recover(goal, "the controller saw an obstacle right ahead", now)
            return
        self._drive(linear, angular)

    def _recover(self, goal: Goal, reason: str, now: float) -> None:
        """Clear the laser obstacles and wait, or abort the goal when the recoveries are used up."""
        self._recoveries += 1
        goal.recoveries = self._recoveries
        self._drive(0.0, 0.0)
        if self._recoveries > self.settings.recovery_retries:
            self._finish(goal, ABORTED, f"{reason}; gave up after {self.settings.recovery_retries} recoveries", now)
            return
        self.costmap.clear_obstacles()
        self.follower.set_path([])
        self._paused_until = self._next_replan = now + self.settings.recovery_wait
        self._progress_anchor, self._progress_since = self.pose[:2], self._paused_until

    def _collision_ahead(self, pose: Pose) -> bool:
        """An obstacle cell in the strip the robot's front sweeps in the next ``collision_lookahead`` metres."""
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        front, half_width = self.base.front, self.base.half_width
        step = self.costmap.resolution / 2.0
        distance = front
        while distance <= front + self.settings.collision_lookahead:
            offset = -half_width
            while offset <= half_width:
                if self.costmap.is_obstacle(x + c * distance - s * offset, y + s * distance + c * offset):
                    return True
                offset += step
            distance += step
        return False

    def _plan_if_needed(self, goal: Goal, pose: Pose, now: float) -> bool:
        """Plan when due or when the path ahead is blocked; False while there is no usable path."""
        blocked = bool(self.follower.path) and any(
            self.costmap.is_lethal(px, py) for px, py in self.follower.remaining(pose, 1.5))
        if self.follower.position_reached or (now < self._next_replan and not blocked and self.follower.path):
            return True
        target = self.follower.goal
        path = plan(self.costmap, (pose[0], pose[1]), (target[0], target[1]))
        if path is None:
            self._recover(goal, f"no path to ({target[0]:.2f}, {target[1]:.2f})", now)
            return False
        self._next_replan = now + self.settings.replan_period
        current = self.follower.remaining(pose, math.inf)
        if (blocked or not current
                or path_length(path) < 0.8 * path_length([(pose[0], pose[1]), *current])):
            self.follower.set_path(path)  # a periodic replan only switches to a clearly shorter path
        if goal.path_length_planned == 0.0:
            goal.path_length_planned = path_length([(pose[0], pose[1]), *path])
        return True

    def _progressing(self, goal: Goal, pose: Pose, now: float) -> bool:
        """Nav2's progress checker; False when it called for a recovery."""
        s = self.settings
        if self.follower.position_reached:
            if self._reached_since is None:
                self._reached_since = now
            if now - self._reached_since > s.progress_timeout:
                self._finish(goal, ABORTED, "could not turn to the goal's heading", now)
                return False
            return True
        ax, ay = self._progress_anchor
        if math.hypot(pose[0] - ax, pose[1] - ay) >= s.progress_radius:
            self._progress_anchor, self._progress_since = (pose[0], pose[1]), now
            return True
        if now - self._progress_since <= s.progress_timeout:
            return True
        self._recover(goal, f"no progress: moved less than {s.progress_radius} m in {s.progress_timeout:g} s", now)
        return False
