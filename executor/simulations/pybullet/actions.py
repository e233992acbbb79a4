"""The ``osc.pybullet`` actions: initialise and run the world, spawn bodies, drive joints, measure distance.

Names and parameters follow the declarations in ``lib_osc/pybullet.osc``. Every action works on the
scenario's :class:`~executor.simulations.pybullet.world.World` (see
:mod:`executor.simulations.pybullet.access`), so the same scenario runs with the wall-clock tick
(``sim.run()`` steps the physics) and step-based (the simulation steps it).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import py_trees

from executor.actions.base import ActionError, VariableHandle
from executor.simulations.pybullet.access import WorldAction
from executor.simulations.pybullet.world import TIME_STEP, scenario_folders

Status = py_trees.common.Status


def _resolve_model(action: WorldAction, model: str) -> Path:
    path = action.world.find_model(model, scenario_folders(action.lease.input_dir))
    if path is None:
        raise ActionError(f"model '{model}' not found (looked in the scenario's folder, the working "
                          "directory and pybullet_data)")
    return path


class SimulationInitialize(WorldAction):
    """``sim.initialize(world)``: load the world's URDF file (e.g. ``plane.urdf``) into the physics."""

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.world_file = ""

    def execute(self, world: str) -> None:
        self.world_file = world

    def update(self) -> Status:
        path = _resolve_model(self, self.world_file)
        self.world.load_urdf(f"{self.actor_name or 'simulation'}.world", path, (0.0, 0.0, 0.0), fixed=True)
        self.feedback_message = f"loaded {path.name}"
        return Status.SUCCESS


class SimulationRun(WorldAction):
    """``sim.run()``: with the wall-clock tick, advance the world by one tick period per tick.

    The tick period (``-s/--step-duration``) must be a whole number of 1/240 s physics steps. In
    step-based mode the simulation advances the world and this action only keeps running.
    """

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.steps_per_tick = 0

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)
        if self.lease.step_based:
            return
        period = kwargs.get("tick_period") or 0.0
        steps = round(period / TIME_STEP)
        if steps < 1 or abs(period / TIME_STEP - steps) > 1e-4:
            raise ActionError(
                f"the tick period of {period} s is not a whole number of PyBullet's 1/240 s steps: "
                "give -s/--step-duration a multiple of 1/240 s (e.g. 0.0041666666667, 0.05 or 0.1)")
        self.steps_per_tick = steps
        self.lease.drive_by_run_action()
        self.logger.debug(f"{steps} physics step(s) per tick")

    def update(self) -> Status:
        world = self.world
        for _ in range(self.steps_per_tick):
            world.step()
        self.feedback_message = f"simulated {world.time:.3f} s"
        return Status.RUNNING


class ActorSpawn(WorldAction):
    """``actor.spawn(model, pose)``: load the URDF file ``model`` at ``pose`` as the actor's body."""

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.model = ""
        self.pose: dict[str, Any] = {}

    def execute(self, model: str, pose: dict[str, Any]) -> None:
        self.model, self.pose = model, pose

    def update(self) -> Status:
        self.lease.catch_up()
        position, orientation = self.pose["position"], self.pose["orientation"]
        path = _resolve_model(self, self.model)
        self.world.load_urdf(self.actor_name, path, (position["x"], position["y"], position["z"]),
                             (orientation["roll"], orientation["pitch"], orientation["yaw"]))
        self.feedback_message = f"spawned {self.model} as '{self.actor_name}'"
        return Status.SUCCESS


class ActorSetJointMotorControl(WorldAction):
    """``actor.set_joint_motor_control(target_velocity, force)``: velocity control on every movable joint.

    The target velocity is given to each joint in its own unit (rad/s for the Husky's wheels), the
    force is the largest force or torque each motor may apply. The motors keep the setting after
    the action ends; the action itself keeps running.
    """

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.target_velocity = 0.0
        self.force = 0.0

    def execute(self, target_velocity: float, force: float) -> None:
        self.target_velocity, self.force = target_velocity, force
        if not (math.isfinite(force) and force >= 0.0):
            raise ActionError(f"force must be a finite number >= 0, got {force}")

    def initialise(self) -> None:
        super().initialise()
        world = self.world
        body = world.body(self.actor_name)
        joints = [joint.index for joint in world.joints(body) if joint.movable]
        world.drive_joints(body, joints, [self.target_velocity] * len(joints), [self.force] * len(joints))
        self.feedback_message = (f"{len(joints)} joint(s) at velocity {self.target_velocity}, "
                                 f"force {self.force}")

    def update(self) -> Status:
        self.lease.catch_up()
        return Status.RUNNING


class ActorDistanceTraveled(WorldAction):
    """``actor.distance_traveled(distance)``: succeed once the body has covered ``distance`` in x-y.

    The distance is the length of the base's path (ground truth), summed over the ticks from
    the action's start.
    """

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.distance = 0.0
        self.traveled = 0.0
        self.previous: tuple[float, float] | None = None

    def execute(self, distance: float) -> None:
        self.distance = distance
        self.traveled = 0.0
        self.previous = None

    def update(self) -> Status:
        self.lease.catch_up()
        world = self.world
        x, y, _ = world.position(world.body(self.actor_name))
        if self.previous is not None:
            self.traveled += math.hypot(x - self.previous[0], y - self.previous[1])
        self.previous = (x, y)
        if self.traveled >= self.distance:
            self.feedback_message = f"traveled {self.traveled:.3f} m >= {self.distance:.3f} m"
            return Status.SUCCESS
        self.feedback_message = f"traveled {self.traveled:.3f} m of {self.distance:.3f} m"
        return Status.RUNNING


class _StoreAction(WorldAction):
    """Base of the actions that store a quantity of the world into a variable (``target_variable``)."""

    #: the action's name in ``osc.pybullet``, for messages
    osc_name = ""

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.resolve_variable_reference_arguments_in_execute = False
        self.target: VariableHandle | None = None

    def execute(self, target_variable: object) -> None:
        if not isinstance(target_variable, VariableHandle):
            raise ActionError(f"{self.osc_name}: target_variable must be a variable (var), got {target_variable!r}")
        self.target = target_variable

    def update(self) -> Status:
        self.lease.catch_up()
        if self.target is None:
            raise ActionError(f"{self.osc_name}: no target variable (execute() was not called)")
        value, self.feedback_message = self.measure()
        self.target.set_value(value)
        return Status.SUCCESS

    def measure(self) -> tuple[object, str]:
        """The value to store, and a line saying what it is."""
        raise NotImplementedError


class SimulationStoreTime(_StoreAction):
    """``sim.store_time(target_variable)``: the world's simulated time into a ``time`` variable."""

    osc_name = "store_time"

    def measure(self) -> tuple[object, str]:
        now = self.world.time
        return now, f"time {now:.3f} s"


class ActorStorePosition(_StoreAction):
    """``actor.store_position(target_variable)``: the body's base position into a ``position_3d`` variable."""

    osc_name = "store_position"

    def measure(self) -> tuple[object, str]:
        world = self.world
        x, y, z = world.position(world.body(self.actor_name))
        return {"x": x, "y": y, "z": z}, f"position ({x:.3f}, {y:.3f}, {z:.3f})"
