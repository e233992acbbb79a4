"""A 2-D laser scanner from the engine's ray casting, and the scan modification used for fault injection.

:class:`Laser` casts ``beams`` horizontal rays over 360° from ``height`` above the robot's base
and reports each beam's range (``inf`` without a return within ``range_max``), as a
``sensor_msgs/LaserScan`` would. The robot's own body is excluded from the rays.

:class:`ScanModification` is the simulated ``laserscan_modification`` node between the laser and
everything that reads the scan: ``random_drop_percentage`` (0..1) replaces that share of the
beams, chosen at random, with ``inf``; ``gaussian_noise_std_deviation`` (metres) adds normal
noise to every range. Its random numbers come from a generator seeded per robot, so a variant
gives the same scans on every run.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from executor.simulations import engines

if TYPE_CHECKING:
    from executor.simulations.engines import FloatArray, RandomGenerator

#: ``(starts, ends) -> hit fraction of each ray`` (0..1, 1.0 without a hit), in world coordinates
RayCast = Callable[[Sequence[Sequence[float]], Sequence[Sequence[float]]], list[float]]


class Laser:
    """Ray-cast ranges around a pose; ``cast(x, y, yaw)`` returns the ranges of all beams."""

    def __init__(self, ray_cast: RayCast, beams: int = 180, range_min: float = 0.15,
                 range_max: float = 12.0, height: float = 0.2) -> None:
        np = engines.numpy()
        self._ray_cast = ray_cast
        self.range_min = range_min
        self.range_max = range_max
        self.height = height
        self.angles: FloatArray = np.linspace(-math.pi, math.pi, beams, endpoint=False)
        self._cos, self._sin = np.cos(self.angles), np.sin(self.angles)

    def cast(self, x: float, y: float, yaw: float) -> FloatArray:
        """The true ranges (no noise) of every beam from pose ``(x, y, yaw)``."""
        np = engines.numpy()
        c, s = math.cos(yaw), math.sin(yaw)
        directions_x = c * self._cos - s * self._sin
        directions_y = s * self._cos + c * self._sin
        z = self.height
        starts = [(x, y, z)] * len(self.angles)
        ends = np.stack((x + directions_x * self.range_max, y + directions_y * self.range_max,
                         np.full(len(self.angles), z)), axis=1).tolist()
        fractions = np.asarray(self._ray_cast(starts, ends))
        ranges = fractions * self.range_max
        ranges[fractions >= 1.0] = np.inf
        return ranges


class ScanModification:
    """The ``laserscan_modification`` node: random drops and Gaussian noise on each scan."""

    NODE = "laserscan_modification"

    def __init__(self, seed: int) -> None:
        self.random_drop_percentage = 0.0
        self.gaussian_noise_std_deviation = 0.0
        self._rng: RandomGenerator = engines.numpy().random.default_rng(seed)

    def apply(self, ranges: FloatArray) -> FloatArray:
        """A modified copy of ``ranges``."""
        np = engines.numpy()
        out = np.array(ranges, dtype=np.float64)
        if self.random_drop_percentage > 0.0:
            count = int(len(out) * self.random_drop_percentage)
            out[self._rng.choice(len(out), size=count, replace=False)] = np.inf
        if self.gaussian_noise_std_deviation > 0.0:
            out = out + self._rng.normal(0.0, self.gaussian_noise_std_deviation, len(out))
        return out
