"""``osc.pybullet``: a PyBullet world for scenarios (DIRECT mode, no display), and its step-based simulation.

``--simulation executor.simulations.pybullet:PyBulletSimulation`` runs a scenario step-based on
PyBullet. The engine is the optional extra ``pybullet``; it is imported only when a world is made.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from executor.simulations.pybullet.simulation import PyBulletSimulation

__all__ = ["PyBulletSimulation"]


def __getattr__(name: str) -> object:
    if name == "PyBulletSimulation":
        from executor.simulations.pybullet.simulation import PyBulletSimulation

        return PyBulletSimulation
    raise AttributeError(f"module 'executor.simulations.pybullet' has no attribute '{name}'")
