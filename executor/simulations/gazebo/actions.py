"""The ``osc.gazebo`` actions on the PyBullet world (``world_name`` is accepted and ignored)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import py_trees

from executor.actions.base import ActionError
from executor.simulations.gazebo.models import UrdfModel, choose
from executor.simulations.pybullet.access import WorldAction
from executor.simulations.pybullet.navigation import NavigationWorld
from executor.simulations.pybullet.world import scenario_folders

Status = py_trees.common.Status


def spawn(action: WorldAction, name: str, model: str, x: float, y: float, z: float, yaw: float) -> None:
    """Spawn ``model`` as ``name``: a URDF as it is, anything else as a box of its size (logged)."""
    NavigationWorld.of(action.lease)  # the ground and the map come first
    world = action.world
    choice = choose(model, scenario_folders(action.lease.input_dir), world.data_path)
    if isinstance(choice, UrdfModel):
        world.load_urdf(name, choice.path, (x, y, z), (0.0, 0.0, yaw))
    else:
        size_x, size_y, size_z = choice.size
        half = (size_x / 2, size_y / 2, size_z / 2)
        world.add_box(name, half, (x, y, max(z, half[2])), yaw, mass=0.0 if choice.static else 1.0, model=model)
    action.logger.info(f"spawned '{name}' at ({x:.2f}, {y:.2f}): {choice.note}")


class SpawnEntity(WorldAction):
    """``actor.spawn(spawn_pose, model, ...)``: the entity is named after the actor."""

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.pose: dict[str, Any] = {}
        self.model = ""

    def execute(self, spawn_pose: dict[str, Any], model: str, world_name: str = "default", xacro_arguments: str = "") -> None:
        self.pose, self.model = spawn_pose, model

    def update(self) -> Status:
        self.lease.catch_up()
        position, orientation = self.pose["position"], self.pose["orientation"]
        spawn(self, self.actor_name, self.model, position["x"], position["y"], position["z"], orientation["yaw"])
        return Status.SUCCESS


class RelativeSpawn(WorldAction):
    """``actor.relative_spawn(frame_id, parent_frame_id, distance, model, ...)``: ``distance`` ahead of a robot."""

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.frame_id = "base_link"
        self.distance = 0.0
        self.model = ""

    def execute(self, distance: float, model: str, frame_id: str = "base_link", parent_frame_id: str = "map",
                world_name: str = "default", xacro_arguments: str = "") -> None:
        self.frame_id, self.distance, self.model = frame_id, distance, model

    def update(self) -> Status:
        self.lease.catch_up()
        navigation = NavigationWorld.of(self.lease)
        robots = sorted(navigation.bases)
        owner = next((r for r in robots if self.frame_id.startswith(f"{r}_") or self.frame_id.startswith(f"{r}/")),
                     robots[0] if len(robots) == 1 else None)
        if owner is None:
            raise ActionError(f"frame '{self.frame_id}': no robot it belongs to (robots: {', '.join(robots) or 'none'})")
        x, y, yaw = navigation.base(owner).true_pose()
        spawn(self, self.actor_name, self.model, x + self.distance * math.cos(yaw),
              y + self.distance * math.sin(yaw), 0.0, yaw)
        return Status.SUCCESS


class DeleteEntity(WorldAction):
    """``actor.delete(entity_name)``."""

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__(associated_actor)
        self.entity = ""

    def execute(self, entity_name: str, world_name: str = "default") -> None:
        self.entity = entity_name

    def update(self) -> Status:
        self.lease.catch_up()
        NavigationWorld.of(self.lease)
        if not self.world.remove(self.entity):
            raise ActionError(f"no entity '{self.entity}' to delete")
        self.logger.info(f"deleted '{self.entity}'")
        return Status.SUCCESS


class ActorExists(WorldAction):
    """``actor_exists(entity_name)``: success when the entity is in the world, failure otherwise."""

    def __init__(self) -> None:
        super().__init__(None)
        self.entity = ""

    def execute(self, entity_name: str, world_name: str = "default") -> None:
        self.entity = entity_name

    def update(self) -> Status:
        self.lease.catch_up()
        NavigationWorld.of(self.lease)
        found = self.entity in self.world.bodies
        self.feedback_message = f"'{self.entity}' {'exists' if found else 'does not exist'}"
        return Status.SUCCESS if found else Status.FAILURE


class WaitForSim(WorldAction):
    """``wait_for_sim(timeout)``: the PyBullet world is up as soon as it is used."""

    def __init__(self) -> None:
        super().__init__(None)

    def execute(self, timeout: float = 60.0, world_name: str = "default") -> None:
        """The world never needs waiting for."""

    def update(self) -> Status:
        self.lease.catch_up()
        NavigationWorld.of(self.lease)
        return Status.SUCCESS


class SpawnMultiple(WorldAction):
    """``spawn_multiple(entities)``: every ``spawn_entity`` of the list, each named by its ``entity_name``."""

    def __init__(self) -> None:
        super().__init__(None)
        self.entities: list[dict[str, Any]] = []

    def execute(self, entities: list[dict[str, Any]], world_name: str = "default") -> None:
        self.entities = list(entities)

    def update(self) -> Status:
        self.lease.catch_up()
        for entity in self.entities:
            position, orientation = entity["spawn_pose"]["position"], entity["spawn_pose"]["orientation"]
            spawn(self, entity["entity_name"], entity["model"], position["x"], position["y"], position["z"],
                  orientation["yaw"])
        return Status.SUCCESS
