"""Step-based PyBullet: ``--simulation executor.simulations.pybullet:PyBulletSimulation``.

One :meth:`~PyBulletSimulation.step` is one physics step of 1/240 s, so a scenario runs as fast as
the engine and ``timeout``/``wait elapsed`` count simulated seconds. Each scenario gets a fresh
:class:`~executor.simulations.pybullet.world.World` in :meth:`~PyBulletSimulation.reset`, which the
``osc.pybullet``, ``osc.ros``, ``osc.nav2`` and ``osc.gazebo`` actions find through their
``setup(simulation=...)`` argument (:mod:`executor.simulations.pybullet.access`).
"""

from __future__ import annotations

from typing import Any

from executor.runtime.simulation import SimulationError, SimulationInterface
from executor.simulations import engines
from executor.simulations.pybullet.world import TIME_STEP, World


class PyBulletSimulation(SimulationInterface):
    """A PyBullet world advanced one fixed step per tick; a new world for every scenario."""

    def __init__(self) -> None:
        self.world: World | None = None

    @property
    def dt(self) -> float:
        return TIME_STEP

    def setup(self, **kwargs: Any) -> None:
        engines.pybullet()  # fail before the first scenario when the extra is missing

    def reset(self, **parameters: Any) -> None:
        """A fresh world; the scenario's parameters are not needed (its actions build the world)."""
        self._close()
        self.world = World(driver="simulation")

    def step(self) -> None:
        if self.world is None:
            raise SimulationError("PyBulletSimulation.step() before reset(): there is no world to step")
        self.world.step()

    def shutdown(self) -> None:
        self._close()

    def _close(self) -> None:
        if self.world is not None:
            self.world.close()
            self.world = None
