"""Where the robot thinks it is: odometry dead reckoning, or a particle filter on a known map (AMCL).

Both take odometry increments (:meth:`predict`) and scans (:meth:`correct`) and give a pose
estimate in the map frame. :class:`DeadReckoning` ignores scans: it is used for SLAM (the map is
built from the scans at the odometry pose) and on maps without walls to localise against.
:class:`ParticleFilter` is Monte Carlo localisation with the likelihood-field sensor model:
particles move with noisy odometry; after the robot has moved ``update_min_d`` metres or turned
``update_min_a`` radians each particle is weighted by how close the scan's end points fall to
the map's walls, and the set is resampled when the weights get uneven. With a noisy or thinned
scan the weights are less informative and the estimate wanders, as AMCL's does.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Protocol

from executor.simulations import engines
from executor.simulations.navigation.costmap import grow_distance
from executor.simulations.navigation.maps import OccupancyMap

if TYPE_CHECKING:
    from executor.simulations.engines import FloatArray, RandomGenerator


def wrap(angle: float) -> float:
    """``angle`` in [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def compose(pose: tuple[float, float, float], delta: tuple[float, float, float]) -> tuple[float, float, float]:
    """``pose`` moved by ``delta`` given in the pose's own frame."""
    x, y, yaw = pose
    dx, dy, dyaw = delta
    c, s = math.cos(yaw), math.sin(yaw)
    return x + c * dx - s * dy, y + s * dx + c * dy, wrap(yaw + dyaw)


class Localizer(Protocol):
    """What the navigation stack needs of a localisation: a pose, odometry in, scans in."""

    @property
    def pose(self) -> tuple[float, float, float]: ...

    def predict(self, delta: tuple[float, float, float]) -> None: ...

    def correct(self, angles: FloatArray, ranges: FloatArray, range_max: float) -> None: ...


class DeadReckoning:
    """The initial pose moved by odometry; scans are not used."""

    def __init__(self, initial: tuple[float, float, float]) -> None:
        self.pose: tuple[float, float, float] = initial

    def predict(self, delta: tuple[float, float, float]) -> None:
        self.pose = compose(self.pose, delta)

    def correct(self, angles: FloatArray, ranges: FloatArray, range_max: float) -> None:
        """Nothing to correct against."""


class ParticleFilter:
    """Monte Carlo localisation on ``grid_map`` (see the module docstring)."""

    def __init__(self, grid_map: OccupancyMap, initial: tuple[float, float, float], seed: int,
                 particles: int = 200, max_beams: int = 60, sigma_hit: float = 0.2, z_hit: float = 0.95,
                 z_rand: float = 0.05, alphas: tuple[float, float, float, float] = (0.2, 0.2, 0.2, 0.2),
                 update_min_d: float = 0.1, update_min_a: float = 0.1) -> None:
        np = engines.numpy()
        self.map = grid_map
        self.rng: RandomGenerator = np.random.default_rng(seed)
        self.count = particles
        self.max_beams = max_beams
        self.sigma_hit, self.z_hit, self.z_rand = sigma_hit, z_hit, z_rand
        self.alphas = alphas
        self.update_min_d, self.update_min_a = update_min_d, update_min_a
        # the likelihood field, on cells of at most 5 cm so that end points are placed finely
        self._scale = max(1, int(round(grid_map.resolution / 0.05)))
        self._field_resolution = grid_map.resolution / self._scale
        occupied = np.kron(grid_map.occupied, np.ones((self._scale, self._scale), dtype=bool))
        max_cells = int(math.ceil(1.0 / self._field_resolution))
        self._distance: FloatArray = grow_distance(occupied, max_cells).astype(np.float64) * self._field_resolution
        self._max_distance = (max_cells + 1) * self._field_resolution
        x, y, yaw = initial
        self.particles: FloatArray = np.column_stack((self.rng.normal(x, 0.1, particles), self.rng.normal(y, 0.1, particles),
                                          self.rng.normal(yaw, 0.05, particles)))
        self.weights: FloatArray = np.full(particles, 1.0 / particles)
        self._moved_d = 0.0
        self._moved_a = 0.0
        self.pose: tuple[float, float, float] = initial

    def predict(self, delta: tuple[float, float, float]) -> None:
        """Move every particle by the odometry increment plus noise.

        ``delta`` is ``(forward, sideways, turn)`` in the robot's frame. The distance moved gets
        noise from itself (``alpha3``) and from turning (``alpha4``), the turn from itself
        (``alpha1``) and from the distance (``alpha2``); half the turn is applied before the move
        and half after.
        """
        np = engines.numpy()
        forward, sideways, turn = delta
        distance = math.hypot(forward, sideways)
        if distance < 1e-9 and abs(turn) < 1e-9:
            return
        a1, a2, a3, a4 = self.alphas
        n = self.count
        turn_sd = math.sqrt(a1 * turn ** 2 + a2 * distance ** 2)
        scale_sd = math.sqrt(a3 + a4 * turn ** 2 / max(distance ** 2, 1e-12)) if distance > 1e-9 else 0.0
        turns = turn + self.rng.normal(0.0, turn_sd, n) if turn_sd > 0 else np.full(n, turn)
        scale = 1.0 + self.rng.normal(0.0, min(scale_sd, 1.0), n) if scale_sd > 0 else np.ones(n)
        p = self.particles
        heading = p[:, 2] + turns / 2.0
        c, s = np.cos(heading), np.sin(heading)
        p[:, 0] += scale * (c * forward - s * sideways)
        p[:, 1] += scale * (s * forward + c * sideways)
        p[:, 2] = (heading + turns / 2.0 + math.pi) % (2.0 * math.pi) - math.pi
        self._moved_d += distance
        self._moved_a += abs(turn)
        self._estimate()

    def correct(self, angles: FloatArray, ranges: FloatArray, range_max: float) -> None:
        """Weight the particles by the scan (once the robot has moved enough) and resample."""
        if self._moved_d < self.update_min_d and self._moved_a < self.update_min_a:
            return
        np = engines.numpy()
        valid = np.flatnonzero(np.isfinite(ranges) & (ranges > 0.0) & (ranges < range_max))
        if valid.size == 0:
            return
        self._moved_d = self._moved_a = 0.0
        chosen = valid[np.linspace(0, valid.size - 1, min(self.max_beams, valid.size)).astype(int)]
        beam_angles, beam_ranges = angles[chosen], ranges[chosen]
        p = self.particles
        heading = p[:, 2:3] + beam_angles[None, :]
        ex = p[:, 0:1] + beam_ranges[None, :] * np.cos(heading)
        ey = p[:, 1:2] + beam_ranges[None, :] * np.sin(heading)
        grid = self.map
        rows = np.floor((ey - grid.origin_y) / self._field_resolution).astype(np.int64)
        cols = np.floor((ex - grid.origin_x) / self._field_resolution).astype(np.int64)
        n_rows, n_cols = self._distance.shape
        inside = (rows >= 0) & (rows < n_rows) & (cols >= 0) & (cols < n_cols)
        distance = np.full(ex.shape, self._max_distance)
        distance[inside] = self._distance[rows[inside], cols[inside]]
        probability = self.z_hit * np.exp(-distance ** 2 / (2.0 * self.sigma_hit ** 2)) + self.z_rand / range_max
        # AMCL's combination: the sum of cubes keeps one bad beam from vetoing a particle
        likelihood = 1.0 + (probability ** 3).sum(axis=1)
        weights = self.weights * likelihood
        total = weights.sum()
        if not math.isfinite(total) or total <= 0.0:
            weights = np.full(self.count, 1.0 / self.count)
        else:
            weights = weights / total
        self.weights = weights
        if 1.0 / float((weights ** 2).sum()) < self.count / 2.0:
            self._resample()
        self._estimate()

    def _resample(self) -> None:
        """Low-variance resampling."""
        np = engines.numpy()
        n = self.count
        positions = (self.rng.random() + np.arange(n)) / n
        indices = np.searchsorted(np.cumsum(self.weights), positions)
        self.particles = self.particles[np.minimum(indices, n - 1)].copy()
        self.weights = np.full(n, 1.0 / n)

    def _estimate(self) -> None:
        np = engines.numpy()
        w = self.weights
        p = self.particles
        yaw = math.atan2(float((w * np.sin(p[:, 2])).sum()), float((w * np.cos(p[:, 2])).sum()))
        self.pose = (float((w * p[:, 0]).sum()), float((w * p[:, 1]).sum()), yaw)
