"""How an action finds the PyBullet world of its scenario.

Step-based (``--simulation …:PyBulletSimulation``) the world belongs to the simulation, which
creates it per scenario. With the wall-clock tick there is no simulation object, so the actions of
one scenario share a world kept per scenario context: each action holds a :class:`WorldLease`
from ``setup`` to ``shutdown``, the world is created when it is first used, and it is closed when
the last action of the scenario lets go (the runtime calls every action's ``shutdown`` at the end).
"""

from __future__ import annotations

import weakref
from collections.abc import Mapping
from typing import Any, Protocol

from executor.actions.base import ActionBase, ActionError
from executor.runtime.simulation import Clock
from executor.simulations.pybullet.simulation import PyBulletSimulation
from executor.simulations.pybullet.world import World


class LineLogger(Protocol):
    """What the simulation libraries log through (the scenario's logger, handed to ``setup``)."""

    def info(self, msg: str) -> None: ...


class _Shared:
    """The wall-clock world of one scenario and how many actions hold it."""

    __slots__ = ("world", "users", "driver")

    def __init__(self) -> None:
        self.world: World | None = None
        self.users = 0
        self.driver = "clock"


#: scenario context -> its wall-clock world (forgotten with the context)
_SHARED: weakref.WeakKeyDictionary[object, _Shared] = weakref.WeakKeyDictionary()


class WorldLease:
    """An action's hold on its scenario's world; made in ``setup(**kwargs)``, released in ``shutdown``.

    The world comes from one of two sources: the step-based :class:`PyBulletSimulation`, or the
    scenario's shared wall-clock world.
    """

    def __init__(self, setup_kwargs: Mapping[str, Any]) -> None:
        self.input_dir: str | None = setup_kwargs.get("input_dir")
        self.output_dir: str | None = setup_kwargs.get("output_dir")
        self.clock: Clock | None = setup_kwargs.get("clock")
        self.logger: LineLogger | None = setup_kwargs.get("logger")
        simulation = setup_kwargs.get("simulation")
        self._source: PyBulletSimulation | _Shared
        if simulation is not None:
            if not isinstance(simulation, PyBulletSimulation):
                raise ActionError(
                    f"this action runs on PyBullet, but the scenario is driven by --simulation "
                    f"{type(simulation).__name__}; use executor.simulations.pybullet:PyBulletSimulation "
                    "or no --simulation")
            self._source = simulation
        else:
            context = setup_kwargs.get("context")
            if context is None:
                raise ActionError("no scenario context in setup(): cannot share a PyBullet world")
            shared = _SHARED.get(context)
            if shared is None:
                shared = _SHARED[context] = _Shared()
            shared.users += 1
            self._source = shared
        self._released = False

    @property
    def step_based(self) -> bool:
        """True when a step-based simulation advances the world (the action never steps it)."""
        return isinstance(self._source, PyBulletSimulation)

    @property
    def world(self) -> World:
        """The world, created on first use."""
        source = self._source
        if isinstance(source, PyBulletSimulation):
            if source.world is None:
                raise ActionError("the PyBullet simulation has no world (reset() was not called)")
            return source.world
        if source.world is None:
            source.world = World(driver=source.driver)
        return source.world

    def drive_by_run_action(self) -> None:
        """``sim.run()`` advances this scenario's world, one tick period per tick."""
        source = self._source
        if isinstance(source, _Shared):
            source.driver = "run_action"
            if source.world is not None:
                source.world.driver = "run_action"

    def catch_up(self) -> None:
        """Let a clock-driven world reach the scenario clock's time (no effect otherwise)."""
        source = self._source
        if isinstance(source, _Shared) and source.world is not None and self.clock is not None:
            source.world.catch_up(self.clock.now())

    def release(self) -> None:
        """Let go of the world; the last holder closes it."""
        source = self._source
        if self._released or not isinstance(source, _Shared):
            return
        self._released = True
        source.users -= 1
        if source.users <= 0 and source.world is not None:
            world, source.world = source.world, None
            world.close()


class WorldAction(ActionBase):
    """Base of the actions that work on the scenario's PyBullet world.

    Holds a :class:`WorldLease` from ``setup`` to ``shutdown`` (subclasses that override either
    call ``super()``). ``actor_name`` is the associated actor's instance name, the name its body
    has in the world.
    """

    def __init__(self, associated_actor: Mapping[str, Any] | None = None) -> None:
        super().__init__()
        self.actor_name: str = (associated_actor or {}).get("name", "")
        self._lease: WorldLease | None = None

    def setup(self, **kwargs: Any) -> None:
        self._lease = WorldLease(kwargs)

    def shutdown(self) -> None:
        if self._lease is not None:
            self._lease.release()

    @property
    def lease(self) -> WorldLease:
        """The hold on the world taken in ``setup``."""
        if self._lease is None:
            raise ActionError(f"{self.name}: the runtime did not call setup() before using the PyBullet world")
        return self._lease

    @property
    def world(self) -> World:
        return self.lease.world
