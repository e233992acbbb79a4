"""The costmap the planner and the path follower look at: map walls plus what the laser sees.

Layers, as in Nav2's costmap:

static
    the occupancy map's walls (localisation on a known map), or nothing (SLAM: the map is what
    the laser has seen so far);
obstacles
    cells where laser beams ended within ``obstacle_max_range`` (marking), emptied again when a
    later beam passes through them within ``raytrace_max_range`` (clearing). Beams without a
    return (``inf``, or ``nan``) neither mark nor clear, as with Nav2's defaults;
inflation
    cells closer to an obstacle than the robot's radius are *lethal* (the robot's centre may not
    go there); up to ``inflation_radius`` a cost falls off so paths keep their distance.

Distances are octagonal approximations of the Euclidean distance (alternating 4- and
8-neighbour growth), good to a few percent and cheap with numpy. Obstacle inflation is kept
incrementally: marking or clearing a cell adds or removes a disk stamp in a count grid.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from executor.simulations import engines
from executor.simulations.navigation.maps import OccupancyMap

if TYPE_CHECKING:
    from executor.simulations.engines import BoolArray, FloatArray, IntArray


def grow_distance(occupied: BoolArray, max_cells: int) -> IntArray:
    """Distance in cells from each cell to the nearest occupied one (``max_cells + 1`` beyond)."""
    np = engines.numpy()
    distance = np.full(occupied.shape, max_cells + 1, dtype=np.int16)
    current = occupied.copy()
    distance[current] = 0
    for step in range(1, max_cells + 1):
        grown = current.copy()
        grown[1:, :] |= current[:-1, :]
        grown[:-1, :] |= current[1:, :]
        grown[:, 1:] |= current[:, :-1]
        grown[:, :-1] |= current[:, 1:]
        if step % 2 == 0:  # diagonal growth every other step: an octagon, close to a circle
            grown[1:, 1:] |= current[:-1, :-1]
            grown[1:, :-1] |= current[:-1, 1:]
            grown[:-1, 1:] |= current[1:, :-1]
            grown[:-1, :-1] |= current[1:, 1:]
        distance[grown & ~current] = step
        current = grown
    return distance


def _disk(radius_cells: int) -> IntArray:
    """1 in the cells within ``radius_cells`` of the centre cell, 0 elsewhere (a square of side 2r+1)."""
    np = engines.numpy()
    r = radius_cells
    rows, cols = np.mgrid[-r:r + 1, -r:r + 1]
    return (rows * rows + cols * cols <= r * r + r).astype(np.int16)


class Costmap:
    """Static walls, laser obstacles and inflation on the occupancy map's grid."""

    def __init__(self, grid_map: OccupancyMap, use_static: bool, robot_radius: float,
                 inflation_radius: float, obstacle_max_range: float = 2.5,
                 raytrace_max_range: float = 3.0) -> None:
        np = engines.numpy()
        self.map = grid_map
        self.resolution = res = grid_map.resolution
        self.obstacle_max_range = obstacle_max_range
        self.raytrace_max_range = raytrace_max_range
        self.lethal_cells = max(1, math.ceil(robot_radius / res))
        self.inflation_cells = max(self.lethal_cells, math.ceil(inflation_radius / res))
        shape = grid_map.shape
        static: BoolArray = grid_map.occupied if use_static else np.zeros(shape, dtype=bool)
        self.static_occupied = static
        static_distance = grow_distance(static, self.inflation_cells)
        self.static_lethal = static_distance <= self.lethal_cells
        self.static_penalty = self._penalty(static_distance)
        self.obstacles: BoolArray = np.zeros(shape, dtype=bool)
        self._lethal_count: IntArray = np.zeros(shape, dtype=np.int16)
        self._near_count: IntArray = np.zeros(shape, dtype=np.int16)
        self._lethal_disk = _disk(self.lethal_cells)
        self._near_disk = _disk(self.inflation_cells)
        self.version = 0  # bumped on every change, so users can cache derived grids

    def _penalty(self, distance: IntArray) -> FloatArray:
        """Cost added for being ``distance`` cells from an obstacle: high close by, 0 at the inflation radius."""
        np = engines.numpy()
        span = max(1, self.inflation_cells - self.lethal_cells)
        closeness = np.clip((self.inflation_cells - distance.astype(np.float64)) / span, 0.0, 1.0)
        return 3.0 * closeness * closeness

    # -- the laser's obstacles -------------------------------------------------------------------

    def update(self, x: float, y: float, yaw: float, angles: FloatArray, ranges: FloatArray,
               range_min: float) -> None:
        """Mark where beams end (within obstacle_max_range) and clear the cells they passed."""
        np = engines.numpy()
        valid = np.isfinite(ranges) & (ranges >= range_min)
        if not valid.any():
            return
        angles, ranges = angles[valid] + yaw, ranges[valid]
        cos, sin = np.cos(angles), np.sin(angles)
        res = self.resolution
        grid = self.map
        rows, cols = grid.shape
        # clearing: sample each beam every half cell up to just before its end
        clear_to = np.minimum(ranges - res, self.raytrace_max_range)
        longest = float(clear_to.max()) if clear_to.size else 0.0
        if longest > 0:
            samples = np.arange(0.0, longest, res * 0.5)
            distances = samples[None, :]
            keep = distances < clear_to[:, None]
            px = (x + cos[:, None] * distances)[keep]
            py = (y + sin[:, None] * distances)[keep]
            r = np.floor((py - grid.origin_y) / res).astype(np.int64)
            c = np.floor((px - grid.origin_x) / res).astype(np.int64)
            inside = (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
            cells = np.unique(r[inside] * cols + c[inside])
            marked = cells[self.obstacles.ravel()[cells]]
            for cell in marked.tolist():
                self._set(cell // cols, cell % cols, False)
        # marking
        close = ranges <= self.obstacle_max_range
        if close.any():
            ex = x + cos[close] * ranges[close]
            ey = y + sin[close] * ranges[close]
            r = np.floor((ey - grid.origin_y) / res).astype(np.int64)
            c = np.floor((ex - grid.origin_x) / res).astype(np.int64)
            inside = (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
            cells = np.unique(r[inside] * cols + c[inside])
            fresh = cells[~self.obstacles.ravel()[cells]]
            for cell in fresh.tolist():
                self._set(cell // cols, cell % cols, True)

    def _set(self, row: int, col: int, occupied: bool) -> None:
        self.obstacles[row, col] = occupied
        sign = 1 if occupied else -1
        for disk, counts in ((self._lethal_disk, self._lethal_count), (self._near_disk, self._near_count)):
            r = disk.shape[0] // 2
            rows, cols = counts.shape
            r0, r1, c0, c1 = row - r, row + r + 1, col - r, col + r + 1
            dr0, dc0 = max(0, -r0), max(0, -c0)
            dr1, dc1 = disk.shape[0] - max(0, r1 - rows), disk.shape[1] - max(0, c1 - cols)
            counts[max(0, r0):min(rows, r1), max(0, c0):min(cols, c1)] += sign * disk[dr0:dr1, dc0:dc1]
        self.version += 1

    def clear_obstacles(self) -> None:
        """Forget everything the laser marked (Nav2's "clear costmap" recovery)."""
        self.obstacles[:] = False
        self._lethal_count[:] = 0
        self._near_count[:] = 0
        self.version += 1

    # -- what the planner and the follower read ---------------------------------------------------

    def lethal(self) -> BoolArray:
        """Cells the robot's centre must not enter."""
        return self.static_lethal | (self._lethal_count > 0)

    def penalty(self) -> FloatArray:
        """Extra cost per cell for being near an obstacle."""
        return self.static_penalty + (self._near_count > 0) * 1.0

    def is_obstacle(self, x: float, y: float) -> bool:
        """An obstacle (wall or laser mark) in the cell of ``(x, y)``; outside the grid counts as one."""
        row, col = self.map.cell(x, y)
        if not self.map.inside(row, col):
            return True
        return bool(self.static_occupied[row, col] or self.obstacles[row, col])

    def is_lethal(self, x: float, y: float) -> bool:
        row, col = self.map.cell(x, y)
        if not self.map.inside(row, col):
            return True
        return bool(self.static_lethal[row, col] or self._lethal_count[row, col] > 0)
