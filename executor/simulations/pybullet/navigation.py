"""The navigation backend on a PyBullet world: map walls, Husky robots with their stacks, simulated nodes.

One :class:`NavigationWorld` per world (a world service), made by the first ``osc.ros``,
``osc.nav2`` or ``osc.gazebo`` action that needs it:

* the ground (``plane.urdf``) unless the world already has a body loaded from it;
* the occupancy map: ``map.yaml`` from the scenario's folder (or the working directory), its
  occupied cells built into the world as 1 m high static boxes; else an empty plane;
* robots (Husky, :mod:`~executor.simulations.pybullet.husky`) with a
  :class:`~executor.simulations.navigation.stack.RobotStack` each, run by the world at 20 Hz
  (controller) and 10 Hz (laser) of simulated time;
* the simulated nodes ``set_node_parameter`` reaches (:mod:`~executor.simulations.navigation.parameters`);
* topics: every scan and controller step is offered to the subscribers (``bag_record``).
"""

from __future__ import annotations

import zlib
from collections.abc import Callable
from typing import Any

from executor.actions.base import ActionError
from executor.simulations.navigation.maps import MapError, OccupancyMap, empty_map, find_map, load_map
from executor.simulations.navigation.parameters import NodeGraph, Parameter, ParameterNode, at_least, within
from executor.simulations.navigation.stack import RobotStack, StackSettings
from executor.simulations.pybullet.access import LineLogger, WorldLease
from executor.simulations.pybullet.husky import HuskyBase
from executor.simulations.pybullet.world import Vec3, World, scenario_folders

WALL_HEIGHT = 1.0
#: (time, topic, message) -> None
Subscriber = Callable[[float, str, dict[str, Any]], None]


class NavigationWorld:
    """See the module docstring; get it with :meth:`of`."""

    @classmethod
    def of(cls, lease: WorldLease) -> NavigationWorld:
        return lease.world.service(cls, lambda world: cls(world, scenario_folders(lease.input_dir), lease.logger))

    def __init__(self, world: World, folders: list[str], logger: LineLogger | None = None) -> None:
        self.world = world
        self.logger = logger
        self.map = self._load_map(folders)
        self._build_world()
        self.settings = StackSettings()
        self.robots: dict[str, RobotStack] = {}
        self.namespaces: dict[str, str] = {}
        self.bases: dict[str, HuskyBase] = {}
        self.subscribers: list[Subscriber] = []
        self.nodes = NodeGraph()
        self._add_nodes()
        world.every(self.settings.control_period, self._control)
        world.every(self.settings.sense_period, self._sense)

    # -- set-up ---------------------------------------------------------------------------------

    def _load_map(self, folders: list[str]) -> OccupancyMap:
        path = find_map(folders)
        if path is None:
            return empty_map()
        try:
            grid_map = load_map(path)
        except (MapError, OSError) as exc:
            raise ActionError(f"cannot use the map: {exc}") from None
        if self.logger is not None:
            rows, cols = grid_map.shape
            self.logger.info(f"map {path}: {cols}x{rows} cells of {grid_map.resolution} m")
        return grid_map

    def _build_world(self) -> None:
        world = self.world
        if not any(body.model.endswith("plane.urdf") for body in world.bodies.values()):
            ground = world.find_model("plane.urdf")
            if ground is None:
                raise ActionError("'plane.urdf' is missing from pybullet_data")
            world.load_urdf("ground", ground, (0.0, 0.0, 0.0), fixed=True)
        for i, (x0, y0, x1, y1) in enumerate(self.map.rectangles()):
            world.add_box(f"map.wall{i}", ((x1 - x0) / 2, (y1 - y0) / 2, WALL_HEIGHT / 2),
                          ((x0 + x1) / 2, (y0 + y1) / 2, WALL_HEIGHT / 2), model="map wall")

    def _add_nodes(self) -> None:
        def scan_changed(name: str, value: object) -> None:
            for stack in self.robots.values():
                setattr(stack.modification, name, value)

        self.nodes.add(ParameterNode("laserscan_modification", {
            "random_drop_percentage": Parameter(float, 0.0, "share of beams replaced by inf", within(0.0, 1.0)),
            "gaussian_noise_std_deviation": Parameter(float, 0.0, "noise added to every range (m)", at_least(0.0)),
        }, scan_changed))
        follower_names = {"FollowPath.desired_linear_vel": "desired_linear_vel",
                          "FollowPath.max_angular_vel": "max_angular_vel",
                          "general_goal_checker.xy_goal_tolerance": "xy_goal_tolerance",
                          "general_goal_checker.yaw_goal_tolerance": "yaw_goal_tolerance"}

        def controller_changed(name: str, value: object) -> None:
            setattr(self.settings.follower, follower_names[name], value)

        follower = self.settings.follower
        self.nodes.add(ParameterNode("controller_server", {
            name: Parameter(float, getattr(follower, attribute), attribute, at_least(0.01))
            for name, attribute in follower_names.items()}, controller_changed))

    # -- robots ---------------------------------------------------------------------------------

    def base(self, name: str, pose: Vec3 = (0.0, 0.0, 0.0)) -> HuskyBase:
        """The robot ``name``'s body, spawned at ``pose`` when it is not in the world yet."""
        base = self.bases.get(name)
        if base is None:
            base = self.bases[name] = HuskyBase(self.world, name, pose)
            if self.logger is not None:
                self.logger.info(f"spawned robot '{name}' (Husky) at x={pose[0]:.2f} y={pose[1]:.2f} yaw={pose[2]:.2f}")
        return base

    def start_navigation(self, name: str, initial: Vec3, use_map: bool,
                         namespace: str = "") -> RobotStack:
        """(Re)start the robot's navigation, localised at ``initial`` (spawning the robot there if needed)."""
        base = self.base(name, initial)
        seed = zlib.crc32(name.encode())
        stack = RobotStack(name, base, self.map, initial, use_map, seed, self.settings)
        for parameter, value in ((p, v.value) for p, v in self.nodes.nodes["laserscan_modification"].parameters.items()):
            setattr(stack.modification, parameter, value)
        self.robots[name] = stack
        self.namespaces[name] = namespace
        stack.now = self.world.time
        return stack

    def stack(self, name: str) -> RobotStack:
        stack = self.robots.get(name)
        if stack is None:
            raise ActionError(f"robot '{name}' has no navigation: call {name}.init_nav2(...) first")
        return stack

    # -- running --------------------------------------------------------------------------------

    def _control(self) -> None:
        now = self.world.time
        for name, stack in self.robots.items():
            stack.control(now)
            if self.subscribers:
                self._publish_state(now, name, stack)

    def _sense(self) -> None:
        now = self.world.time
        for name, stack in self.robots.items():
            stack.sense(now)
            if self.subscribers and stack.last_scan is not None:
                self._publish(now, name, "scan", {
                    "angle_min": float(stack.laser.angles[0]), "angle_increment": float(
                        stack.laser.angles[1] - stack.laser.angles[0]), "range_max": stack.laser.range_max,
                    "ranges": [r if r == r and abs(r) != float("inf") else None for r in stack.last_scan.tolist()]})

    def _publish_state(self, now: float, name: str, stack: RobotStack) -> None:
        x, y, yaw = stack.base.true_pose()
        ex, ey, eyaw = stack.pose
        ox, oy, oyaw = stack.odometry_pose
        linear, angular = stack.last_command
        self._publish(now, name, "robot_pose_gt", {"x": x, "y": y, "yaw": yaw})
        self._publish(now, name, "robot_pose_loc", {"x": ex, "y": ey, "yaw": eyaw})
        if stack.mode == "amcl":
            self._publish(now, name, "amcl_pose", {"x": ex, "y": ey, "yaw": eyaw})
        self._publish(now, name, "odom", {"x": ox, "y": oy, "yaw": oyaw, "distance": stack.odometry_distance})
        self._publish(now, name, "cmd_vel", {"linear": linear, "angular": angular})
        self._publish(now, name, "tf", {"parent": "map", "child": "base_link", "x": ex, "y": ey, "yaw": eyaw})

    def _publish(self, now: float, name: str, topic: str, message: dict[str, Any]) -> None:
        namespace = self.namespaces.get(name, "")
        full = f"/{namespace}/{topic}" if namespace else f"/{topic}"
        for subscriber in self.subscribers:
            subscriber(now, full, message)
