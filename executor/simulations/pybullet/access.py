"""How an action finds the PyBullet world of its scenario.

Step-based (``--simulation …:PyBulletSimulation``) the world belongs to the simulation, which
creates it per scenario. With the wall-clock tick there is no simulation object, so the actions of
one scenario share a world kept per scenario context: each action holds a :class:`WorldLease`
from ``setup`` to ``shutdown``, the world is created when it is first used, and it is closed when
the last action of the scenario lets go (the runtime calls every action's ``shutdown`` at the end).
"""

from __future__ import annotations

import weakref

from executor.actions.base import ActionBase, ActionError
from executor.simulations.pybullet.simulation import PyBulletSimulation
from executor.simulations.pybullet.world import World


class _Shared:
    """The wall-clock world of one scenario and how many actions hold it."""

    __slots__ = ("world", "users", "driver")

    def __init__(self) -> None:
        self.world: World | None = None
        self.users = 0
        self.driver = "clock"


_SHARED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


class WorldLease:
    """An action's hold on its scenario's world; made in ``setup(**kwargs)``, released in ``shutdown``."""

    def __init__(self, setup_kwargs: dict) -> None:
        self.input_dir: str | None = setup_kwargs.get("input_dir")
        self.output_dir: str | None = setup_kwargs.get("output_dir")
        self.clock = setup_kwargs.get("clock")
        self.logger = setup_kwargs.get("logger")
        self.tick_period: float | None = setup_kwargs.get("tick_period")
        simulation = setup_kwargs.get("simulation")
        self._simulation: PyBulletSimulation | None = None
        self._shared: _Shared | None = None
        if simulation is not None:
            if not isinstance(simulation, PyBulletSimulation):
                raise ActionError(
                    f"this action runs on PyBullet, but the scenario is driven by --simulation "
                    f"{type(simulation).__name__}; use executor.simulations.pybullet:PyBulletSimulation "
                    "or no --simulation")
            self._simulation = simulation
        else:
            context = setup_kwargs.get("context")
            if context is None:
                raise ActionError("no scenario context in setup(): cannot share a PyBullet world")
            shared = _SHARED.get(context)
            if shared is None:
                shared = _SHARED[context] = _Shared()
            shared.users += 1
            self._shared = shared
        self._released = False

    @property
    def step_based(self) -> bool:
        """True when a step-based simulation advances the world (the action never steps it)."""
        return self._simulation is not None

    @property
    def world(self) -> World:
        """The world, created on first use."""
        if self._simulation is not None:
            if self._simulation.world is None:
                raise ActionError("the PyBullet simulation has no world (reset() was not called)")
            return self._simulation.world
        shared = self._shared
        if shared.world is None:
            shared.world = World(driver=shared.driver)
        return shared.world

    def drive_by_run_action(self) -> None:
        """``sim.run()`` advances this scenario's world, one tick period per tick."""
        if self._shared is not None:
            self._shared.driver = "run_action"
            if self._shared.world is not None:
                self._shared.world.driver = "run_action"

    def catch_up(self) -> None:
        """Let a clock-driven world reach the scenario clock's time (no effect otherwise)."""
        shared = self._shared
        if shared is not None and shared.world is not None and self.clock is not None:
            shared.world.catch_up(self.clock.now())

    def release(self) -> None:
        """Let go of the world; the last holder closes it."""
        if self._released or self._shared is None:
            return
        self._released = True
        shared = self._shared
        shared.users -= 1
        if shared.users <= 0 and shared.world is not None:
            world, shared.world = shared.world, None
            world.close()


class WorldAction(ActionBase):
    """Base of the actions that work on the scenario's PyBullet world.

    Holds a :class:`WorldLease` from ``setup`` to ``shutdown`` (subclasses that override either
    call ``super()``). ``actor_name`` is the associated actor's instance name, the name its body
    has in the world.
    """

    def __init__(self, associated_actor: dict | None = None) -> None:
        super().__init__()
        self.actor_name = (associated_actor or {}).get("name", "")
        self.lease: WorldLease | None = None

    def setup(self, **kwargs) -> None:
        self.lease = WorldLease(kwargs)

    def shutdown(self) -> None:
        if self.lease is not None:
            self.lease.release()

    @property
    def world(self) -> World:
        return self.lease.world
