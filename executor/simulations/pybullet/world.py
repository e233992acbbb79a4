"""One PyBullet physics world: a DIRECT client (no display), its named bodies and its fixed-step clock.

A :class:`World` is created per scenario, so every scenario starts from the same state and the
same variant gives the same outcome on every run: the physics advances only by :meth:`World.step`,
a fixed step of :data:`TIME_STEP` seconds, and nothing in it reads the wall clock.

Who advances the world (its :attr:`World.driver`):

``"simulation"``
    the step-based :class:`~executor.simulations.pybullet.simulation.PyBulletSimulation`, one
    :meth:`step` per tick of the scenario (``--simulation``);
``"run_action"``
    ``sim.run()`` of ``osc.pybullet``, a whole tick period of steps per tick (wall-clock tick);
``"clock"``
    nobody in particular: actions call :meth:`catch_up` with the scenario clock's time on every
    tick, so the world keeps pace with the wall clock (navigation scenarios run without ``--simulation``).

Components that must run at a fixed rate in simulated time (a laser, a controller) register with
:meth:`every`; they run inside :meth:`step`, in registration order.

PyBullet has no type information, so every call into it is made here, behind typed methods: the
rest of the simulation code works with a :class:`World` and its :class:`Body` and :class:`Joint`
records, never with the engine module.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

from executor.actions.base import ActionError
from executor.simulations import engines

#: seconds of simulated time per physics step (PyBullet's default, which its URDF models are tuned for)
TIME_STEP = 1.0 / 240.0
GRAVITY = -9.8
#: a point or a vector in the world (metres), or roll/pitch/yaw (radians)
Vec3 = tuple[float, float, float]
#: the class of a component the world keeps one of (see :meth:`World.service`)
Service = TypeVar("Service")


@dataclass
class Body:
    """A body in the world under a name (the actor's name for spawned actors)."""

    name: str
    body_id: int
    model: str
    #: half extents of a box stand-in (``None`` for a loaded model)
    box: Vec3 | None = None


@dataclass(frozen=True)
class Joint:
    """A joint of a body: its index in the body, its name in the model and whether it can move."""

    index: int
    name: str
    movable: bool


@dataclass
class _Periodic:
    period_steps: int
    callback: Callable[[], None]


class World:
    """A PyBullet world in DIRECT mode; see the module docstring."""

    def __init__(self, driver: str = "clock") -> None:
        self._p = engines.pybullet()
        self.data_path = engines.pybullet_data_path()
        with engines.native_output_silenced():
            client = self._p.connect(self._p.DIRECT)
        if client < 0:
            raise ActionError("cannot start a PyBullet physics client")
        self.client: int = client
        self._p.setGravity(0.0, 0.0, GRAVITY, physicsClientId=client)
        self._p.setTimeStep(TIME_STEP, physicsClientId=client)
        self.driver = driver
        self.steps = 0
        self.bodies: dict[str, Body] = {}
        self.services: dict[type, object] = {}
        self._periodic: list[_Periodic] = []
        self._closers: list[Callable[[], None]] = []
        self.closed = False

    # -- time ----------------------------------------------------------------------------------

    @property
    def dt(self) -> float:
        return TIME_STEP

    @property
    def time(self) -> float:
        """Simulated seconds since the world was created (steps × dt: no accumulated rounding)."""
        return self.steps * TIME_STEP

    def step(self) -> None:
        """Advance the physics by one fixed step, then run the components that are due."""
        self._p.stepSimulation(physicsClientId=self.client)
        self.steps += 1
        for periodic in self._periodic:
            if self.steps % periodic.period_steps == 0:
                periodic.callback()

    def step_for(self, seconds: float) -> None:
        """Advance by ``seconds`` (rounded to whole steps)."""
        for _ in range(round(seconds / TIME_STEP)):
            self.step()

    def catch_up(self, now: float) -> None:
        """With driver ``"clock"``: step until simulated time reaches ``now`` (else nothing)."""
        if self.driver != "clock":
            return
        target = math.floor(now / TIME_STEP + 1e-9)
        while self.steps < target:
            self.step()

    def every(self, period: float, callback: Callable[[], None]) -> None:
        """Call ``callback`` every ``period`` seconds of simulated time (rounded to whole steps)."""
        self._periodic.append(_Periodic(max(1, round(period / TIME_STEP)), callback))

    def on_close(self, callback: Callable[[], None]) -> None:
        """Call ``callback`` when the world closes (flush a recording)."""
        self._closers.append(callback)

    def service(self, kind: type[Service], factory: Callable[[World], Service]) -> Service:
        """The world's single instance of the component class ``kind`` (the navigation), made on first use."""
        found = self.services.get(kind)
        if isinstance(found, kind):
            return found
        made = factory(self)
        self.services[kind] = made
        return made

    # -- bodies --------------------------------------------------------------------------------

    def find_model(self, model: str, folders: Iterable[str | None] = ()) -> Path | None:
        """The file ``model`` names: absolute, else in ``folders`` (the scenario's), else in pybullet_data."""
        path = Path(model)
        if path.is_absolute():
            return path if path.is_file() else None
        for folder in [*folders, self.data_path]:
            if folder and (Path(folder) / path).is_file():
                return Path(folder) / path
        return None

    def load_urdf(self, name: str, path: Path, position: Vec3, rpy: Vec3 = (0.0, 0.0, 0.0),
                  fixed: bool = False) -> Body:
        """Load a URDF file as the body ``name`` (replacing nothing: the name must be free)."""
        self._check_free(name)
        quaternion = self._p.getQuaternionFromEuler(rpy)
        try:
            with engines.native_output_silenced():
                body_id = self._p.loadURDF(str(path), position, quaternion, useFixedBase=fixed,
                                           physicsClientId=self.client)
        except self._p.error as exc:
            raise ActionError(f"PyBullet cannot load '{path}': {exc}") from exc
        body = self.bodies[name] = Body(name, body_id, str(path))
        return body

    def add_box(self, name: str, half_extents: Vec3, position: Vec3, yaw: float = 0.0, mass: float = 0.0,
                model: str = "box") -> Body:
        """A box body (``mass`` 0: static) centred at ``position``."""
        self._check_free(name)
        p, client = self._p, self.client
        shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=half_extents, physicsClientId=client)
        body_id = p.createMultiBody(baseMass=mass, baseCollisionShapeIndex=shape, basePosition=position,
                                    baseOrientation=p.getQuaternionFromEuler((0.0, 0.0, yaw)),
                                    physicsClientId=client)
        body = self.bodies[name] = Body(name, body_id, model, half_extents)
        return body

    def remove(self, name: str) -> bool:
        """Remove the body ``name``; False when there is none."""
        body = self.bodies.pop(name, None)
        if body is None:
            return False
        self._p.removeBody(body.body_id, physicsClientId=self.client)
        return True

    def body(self, name: str) -> Body:
        found = self.bodies.get(name)
        if found is None:
            known = ", ".join(sorted(self.bodies)) or "none"
            raise ActionError(f"no body '{name}' in the PyBullet world (bodies: {known})")
        return found

    def _check_free(self, name: str) -> None:
        if name in self.bodies:
            raise ActionError(f"the PyBullet world already has a body '{name}'")

    # -- joints and links ----------------------------------------------------------------------

    def joints(self, body: Body) -> list[Joint]:
        """The body's joints in index order."""
        p, client = self._p, self.client
        found: list[Joint] = []
        for index in range(p.getNumJoints(body.body_id, physicsClientId=client)):
            info = p.getJointInfo(body.body_id, index, physicsClientId=client)
            found.append(Joint(index, info[1].decode(), info[2] != p.JOINT_FIXED))
        return found

    def drive_joints(self, body: Body, joints: Sequence[int], velocities: Sequence[float],
                     forces: Sequence[float]) -> None:
        """Velocity control: each joint's motor turns it at its velocity, with at most its force (or torque)."""
        if not joints:
            return
        self._p.setJointMotorControlArray(body.body_id, list(joints), self._p.VELOCITY_CONTROL,
                                          targetVelocities=list(velocities), forces=list(forces),
                                          physicsClientId=self.client)

    def set_collision_group(self, body: Body, group: int, mask: int = 0xFFFF) -> None:
        """Put the body's base and every link in collision filter ``group`` (see :meth:`ray_cast`)."""
        for link in range(-1, self._p.getNumJoints(body.body_id, physicsClientId=self.client)):
            self._p.setCollisionFilterGroupMask(body.body_id, link, group, mask, physicsClientId=self.client)

    def set_anisotropic_friction(self, body: Body, link: int, friction: Vec3) -> None:
        """Scale the link's friction per direction of its own frame (a wheel's rolling direction, its axle)."""
        self._p.changeDynamics(body.body_id, link, anisotropicFriction=list(friction), physicsClientId=self.client)

    # -- state ---------------------------------------------------------------------------------

    def position(self, body: Body) -> Vec3:
        (x, y, z), _ = self._p.getBasePositionAndOrientation(body.body_id, physicsClientId=self.client)
        return x, y, z

    def pose_2d(self, body: Body) -> Vec3:
        """``(x, y, yaw)`` of the body's base."""
        position, quaternion = self._p.getBasePositionAndOrientation(body.body_id, physicsClientId=self.client)
        x, y, z, w = quaternion
        yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
        return position[0], position[1], yaw

    def velocity_2d(self, body: Body) -> Vec3:
        """``(forward speed, sideways speed, yaw rate)`` of the body's base in its own frame."""
        linear, angular = self._p.getBaseVelocity(body.body_id, physicsClientId=self.client)
        _, _, yaw = self.pose_2d(body)
        c, s = math.cos(yaw), math.sin(yaw)
        return c * linear[0] + s * linear[1], -s * linear[0] + c * linear[1], angular[2]

    def ray_cast(self, starts: Sequence[Sequence[float]], ends: Sequence[Sequence[float]],
                 ignore_group: int = 0) -> list[float]:
        """The hit fraction (0..1, 1.0 for no hit) of each ray from ``starts[i]`` to ``ends[i]``.

        Bodies in collision filter group ``ignore_group`` (a sensor's own robot) are not hit.
        """
        fractions: list[float] = []
        limit = self._p.MAX_RAY_INTERSECTION_BATCH_SIZE
        mask = 0xFFFF & ~ignore_group
        for first in range(0, len(starts), limit):
            hits = self._p.rayTestBatch(starts[first:first + limit], ends[first:first + limit],
                                        collisionFilterMask=mask, physicsClientId=self.client)
            fractions.extend(1.0 if hit[0] < 0 else hit[2] for hit in hits)
        return fractions

    # -- end -----------------------------------------------------------------------------------

    def close(self) -> None:
        """Run the close callbacks and disconnect the client (idempotent)."""
        if self.closed:
            return
        self.closed = True
        try:
            for callback in self._closers:
                callback()
        finally:
            try:
                self._p.disconnect(physicsClientId=self.client)
            except self._p.error:
                pass


def scenario_folders(input_dir: str | None) -> list[str]:
    """Folders a scenario's relative file names are looked up in: its own folder, then the working directory."""
    return [d for d in (input_dir, os.getcwd()) if d]
