"""Global planner: A* over the costmap grid, 8-connected, lethal cells forbidden.

The cost of a step is its length times ``1 + penalty`` of the cell entered, so paths keep away
from walls where there is room. The robot may leave the lethal zone it stands in (within its
own radius of the start), as Nav2 clears the robot's footprint. A goal in a lethal cell is moved
to the nearest free cell within ``goal_tolerance`` (NavFn's ``tolerance``); without one, or when
no path exists, :func:`plan` returns ``None``, which the navigator turns into an aborted goal.
"""

from __future__ import annotations

import heapq
import math
from typing import TYPE_CHECKING

from executor.simulations.navigation.costmap import Costmap
from executor.simulations.navigation.maps import OccupancyMap

if TYPE_CHECKING:
    from executor.simulations.engines import BoolArray

_SQRT2 = math.sqrt(2.0)
_MOVES = ((1, 0, 1.0), (-1, 0, 1.0), (0, 1, 1.0), (0, -1, 1.0),
          (1, 1, _SQRT2), (1, -1, _SQRT2), (-1, 1, _SQRT2), (-1, -1, _SQRT2))


def plan(costmap: Costmap, start: tuple[float, float], goal: tuple[float, float],
         goal_tolerance: float = 0.5, max_expansions: int = 400_000) -> list[tuple[float, float]] | None:
    """World points from ``start`` to ``goal`` (cell centres, goal last), or None without a path."""
    grid = costmap.map
    rows, cols = grid.shape
    lethal = costmap.lethal()
    start_cell = grid.cell(*start)
    if not grid.inside(*start_cell):
        return None
    # the robot may drive out of the lethal disk it stands in
    escape = costmap.lethal_cells
    sr, sc = start_cell
    lethal[max(0, sr - escape):sr + escape + 1, max(0, sc - escape):sc + escape + 1] = False
    goal_cell = _free_goal(grid, lethal, goal, goal_tolerance)
    if goal_cell is None:
        return None
    blocked = lethal.ravel().tolist()
    penalty = costmap.penalty().ravel().tolist()
    start_index, goal_index = sr * cols + sc, goal_cell[0] * cols + goal_cell[1]
    gr, gc = goal_cell
    came_from: dict[int, int] = {start_index: -1}
    cost = {start_index: 0.0}
    frontier = [(math.hypot(gr - sr, gc - sc), start_index)]
    expansions = 0
    while frontier:
        _, index = heapq.heappop(frontier)
        if index == goal_index:
            return _path(grid, came_from, index, cols, goal)
        expansions += 1
        if expansions > max_expansions:
            return None
        r, c = divmod(index, cols)
        base = cost[index]
        for dr, dc, length in _MOVES:
            nr, nc = r + dr, c + dc
            if not (0 <= nr < rows and 0 <= nc < cols):
                continue
            neighbour = nr * cols + nc
            if blocked[neighbour]:
                continue
            new_cost = base + length * (1.0 + penalty[neighbour])
            if new_cost < cost.get(neighbour, math.inf):
                cost[neighbour] = new_cost
                came_from[neighbour] = index
                heapq.heappush(frontier, (new_cost + math.hypot(gr - nr, gc - nc), neighbour))
    return None


def _free_goal(grid: OccupancyMap, lethal: BoolArray, goal: tuple[float, float],
               tolerance: float) -> tuple[int, int] | None:
    """The goal's cell, else the nearest cell within ``tolerance`` that is not lethal."""
    row, col = grid.cell(*goal)
    if grid.inside(row, col) and not lethal[row, col]:
        return row, col
    reach = int(math.ceil(tolerance / grid.resolution))
    best: tuple[int, int] | None = None
    best_distance = math.inf
    for dr in range(-reach, reach + 1):
        for dc in range(-reach, reach + 1):
            r, c = row + dr, col + dc
            distance = math.hypot(dr, dc) * grid.resolution
            if distance <= tolerance and distance < best_distance and grid.inside(r, c) and not lethal[r, c]:
                best, best_distance = (r, c), distance
    return best


def _path(grid: OccupancyMap, came_from: dict[int, int], index: int, cols: int,
          goal: tuple[float, float]) -> list[tuple[float, float]]:
    cells: list[tuple[float, float]] = []
    while index != -1:
        cells.append(grid.centre(*divmod(index, cols)))
        index = came_from[index]
    cells.reverse()
    if len(cells) > 1:
        cells = cells[1:]  # the start cell's centre is behind or beside the robot
    end = cells[-1]
    if math.hypot(end[0] - goal[0], end[1] - goal[1]) <= grid.resolution:
        cells[-1] = goal
    return cells


def path_length(points: list[tuple[float, float]]) -> float:
    return sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(points, points[1:], strict=False))
