"""``boundary --pass-rate R --along KEY``: the level of one axis where the share of passing runs crosses ``R``.

A fault-injection sweep asks where the pass rate *over the other axes* falls below a rate: noise 0.4 m, all
pass; noise 0.5 m, 38 % pass. Here the runs are grouped by their level along ``KEY`` and each level's runs
count towards its pass rate over the other axes' cells (the product of their listed values; when that is
more than :data:`RATE_RUNS`, or an axis is a continuous range, a sample of ``RATE_RUNS`` runs stands for them).

A level is *decided* once its runs settle which side of ``R`` it is on whatever its other cells give:
``passed >= ceil(R * cells)`` (at or above the rate) or ``failed > cells - ceil(R * cells)`` (below), so a level
far from the boundary is decided after a few runs and the one beside it after at most all its cells.

Each round guesses where the rate crosses: the split of the ordered levels (and the direction, falling or
rising along the axis) that agrees with every decided level and best fits the others' runs (each run scores
``passed - R`` on the side expected to be at or above the rate); with nothing to go on, the middle of the
levels left (plain bisection), falling first. The levels on both sides of that split get runs on cells not run
yet, as many as could decide them on the side expected. Before any level is decided, the samples left go to
the rest of their cells and then open more levels, spread out (a k-ary search of a wide axis); after, a round
proposes no more than could decide the two, fewer than its samples when that is less: a run spent where the
guess is already settled tells nothing, and the next round guesses again from what these runs give. The boundary is
*located* when the two levels beside the split are decided and adjacent (listed values next to each other, or
no further apart than ``--resolution`` along a continuous range, which is cut into levels that far apart).
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from dataclasses import dataclass

from coverage_engine.search.space import Point, Space
from coverage_engine.search_record import ABOVE, BELOW

#: Runs that stand for a level's pass rate when the other axes have more cells than this (or a continuous one).
RATE_RUNS = 16


@dataclass(frozen=True)
class RateRun:
    """A run where it sits in the unit cube and whether it passed."""

    point: Point
    passed: bool


@dataclass(frozen=True)
class Level:
    """One level along the axis: its coordinate, its runs, how many passed, and which side it is decided on."""

    coordinate: float
    runs: int
    passed: int
    decided: str | None


@dataclass(frozen=True)
class RateBoundary:
    """The split found: the last level on the first side and the first on the other (None when not seen), the
    direction (``falling``: at or above the rate below the split), whether it is located, and every level run."""

    levels: tuple[Level, ...]
    before: Level | None
    after: Level | None
    falling: bool
    located: bool


@dataclass(frozen=True)
class RateProposal:
    points: tuple[Point, ...]
    boundary: RateBoundary


class _Cells:
    """The cells of the other axes: every combination of their listed values, or ``RATE_RUNS`` drawn ones."""

    def __init__(self, space: Space, along: int, rng: random.Random) -> None:
        self.space, self.along = space, along
        others = [space.levels(i) for i in range(len(space.axes)) if i != along]
        product = math.prod(k for k in others if k is not None) if all(k is not None for k in others) else None
        self.exact = product is not None and product <= RATE_RUNS
        self.count = product if self.exact and product is not None else RATE_RUNS
        self.rng = rng

    def key(self, point: Point) -> tuple[float, ...]:
        return tuple(round(u, 9) for i, u in enumerate(point) if i != self.along)

    def fresh(self, coordinate: float, taken: set[tuple[float, ...]], count: int,
              lean: dict[tuple[float, ...], int] | None = None) -> list[Point]:
        """Up to ``count`` points at ``coordinate`` on cells not in ``taken``: those ``lean`` scores highest
        first, in a seeded random order among equals."""
        dims = len(self.space.axes)
        if self.exact:
            grids = [[(j + 0.5) / (self.space.levels(i) or 1) for j in range(self.space.levels(i) or 1)]
                     for i in range(dims) if i != self.along]
            cells = [cell for cell in _product(grids) if tuple(round(u, 9) for u in cell) not in taken]
            self.rng.shuffle(cells)
            if lean:
                cells.sort(key=lambda cell: -lean.get(tuple(round(u, 9) for u in cell), 0))
            return [self._at(coordinate, cell) for cell in cells[:count]]
        points = []
        for _ in range(count):
            point = self.space.snap([coordinate if i == self.along else self.rng.random() for i in range(dims)])
            points.append(point)
        return points

    def _at(self, coordinate: float, cell: Sequence[float]) -> Point:
        values = list(cell)
        values.insert(self.along, coordinate)
        return tuple(values)


def _product(grids: Sequence[Sequence[float]]) -> list[tuple[float, ...]]:
    cells: list[tuple[float, ...]] = [()]
    for grid in grids:
        cells = [cell + (u,) for cell in cells for u in grid]
    return cells


def _coordinates(space: Space, along: int, resolution: float) -> list[float]:
    """The levels along the axis: its listed values' centres, or a range cut ``resolution`` apart."""
    k = space.levels(along)
    if k is not None:
        return [(j + 0.5) / k for j in range(k)]
    steps = max(1, math.ceil(1 / resolution - 1e-9))
    return [j / steps for j in range(steps + 1)]


def _needed(rate: float, cells: int) -> int:
    """Passing runs a level needs to be at or above ``rate`` of its ``cells``."""
    return math.ceil(rate * cells - 1e-9)


def _levels(coordinates: Sequence[float], runs: Sequence[RateRun], along: int, rate: float, cells: int) \
        -> list[Level]:
    counts: dict[int, list[int]] = {}
    for run in runs:
        index = min(range(len(coordinates)), key=lambda j: abs(coordinates[j] - run.point[along]))
        tally = counts.setdefault(index, [0, 0])
        tally[0] += 1
        tally[1] += run.passed
    need = _needed(rate, cells)
    levels = []
    for j, u in enumerate(coordinates):
        total, passed = counts.get(j, [0, 0])
        decided = ABOVE if passed >= need else BELOW if total - passed > cells - need else None
        levels.append(Level(u, total, passed, decided))
    return levels


def _split(levels: Sequence[Level], rate: float) -> tuple[int, bool] | None:
    """``(t, falling)``: the rate crosses between levels ``t - 1`` and ``t``; the split that agrees with every
    decided level and fits the other runs best, the middle of the candidates when nothing tells them apart."""
    best: tuple[float, float, int, bool] | None = None
    for falling in (True, False):
        for t in range(1, len(levels)):
            first, second = levels[:t], levels[t:]
            high, low = (first, second) if falling else (second, first)
            if any(level.decided == BELOW for level in high) or any(level.decided == ABOVE for level in low):
                continue
            fit = sum(level.passed - rate * level.runs for level in high) \
                - sum(level.passed - rate * level.runs for level in low)
            candidate = (round(fit, 9), -abs(t - len(levels) / 2), t, falling)
            if best is None or candidate[:2] > best[:2]:
                best = candidate
    return None if best is None else (best[2], best[3])


def rate_boundary(space: Space, runs: Sequence[RateRun], along: int, rate: float, resolution: float) -> RateBoundary:
    """Where the pass rate along axis ``along`` crosses ``rate``, from the runs so far."""
    cells = _Cells(space, along, random.Random(0)).count
    levels = _levels(_coordinates(space, along, resolution), runs, along, rate, cells)
    split = _split(levels, rate)
    ran = tuple(level for level in levels if level.runs)
    if split is None:
        return RateBoundary(ran, None, None, True, False)
    t, falling = split
    before, after = levels[t - 1], levels[t]
    located = before.decided is not None and after.decided is not None
    seen = any(level.decided == ABOVE for level in levels) and any(level.decided == BELOW for level in levels)
    return RateBoundary(ran, before if seen else None, after if seen else None, falling, located and seen)


def _to_decide(level: Level, expect_above: bool, rate: float, cells: int) -> int:
    """Runs that could decide ``level`` on the side the guess expects (all of them going that way), at least 1."""
    need = _needed(rate, cells)
    if expect_above:
        return max(1, need - level.passed)
    return max(1, cells - need + 1 - (level.runs - level.passed))


def _spread(levels: Sequence[Level], t: int) -> list[int]:
    """The open levels between the decided ones nearest the split, besides the two beside it, farthest from
    every level run or chosen first (a k-ary search of the bracket when a round has samples to spare)."""
    decided = [j for j, level in enumerate(levels) if level.decided is not None]
    low = max((j for j in decided if j < t), default=-1)
    high = min((j for j in decided if j >= t), default=len(levels))
    fixed = [low, high, t - 1, t]
    open_levels = [j for j in range(low + 1, high) if j not in (t - 1, t)]
    chosen: list[int] = []
    while open_levels:
        best = max(open_levels, key=lambda j: (min(abs(j - f) for f in fixed + chosen), -abs(j - t)))
        chosen.append(best)
        open_levels.remove(best)
    return chosen


def _shares(levels: Sequence[Level], t: int, falling: bool, samples: int, rate: float,
            cells: int) -> list[tuple[int, int]]:
    """``(level, runs)`` for a round: the two levels beside the split get what could decide them; before any level
    is decided, also their cells left (the one whose rate so far is nearest ``rate`` first, on a tie the one that
    needed more), then more levels of the bracket, each with what could decide it."""
    def room(j: int) -> int:
        return max(0, cells - levels[j].runs) if levels[j].decided is None else 0

    def expect_above(j: int) -> bool:
        return (j < t) == falling

    shares: dict[int, int] = {}

    def give(j: int, count: int) -> None:
        nonlocal samples
        count = min(count, room(j) - shares.get(j, 0), samples)
        if count > 0:
            shares[j] = shares.get(j, 0) + count
            samples -= count

    beside = [t - 1, t]
    first = {j: _to_decide(levels[j], expect_above(j), rate, cells) for j in beside}
    for j in beside:
        give(j, first[j])
    if any(level.decided for level in levels):
        return sorted(shares.items())
    for j in sorted(beside, key=lambda j: (abs(levels[j].passed / levels[j].runs - rate) if levels[j].runs else 0,
                                           -first[j])):
        give(j, room(j))
    for j in _spread(levels, t):
        give(j, _to_decide(levels[j], expect_above(j), rate, cells))
    return sorted(shares.items())


def _lean(runs: Sequence[RateRun], coordinates: Sequence[float], along: int, cells: _Cells, j: int, falling: bool,
          expect_above: bool) -> dict[tuple[float, ...], int]:
    """Which cells of level ``j`` to run first: those likeliest to decide it on the side expected. A cell that
    passed further along the falling direction (where passing is harder) or failed before it (where it is
    easier) hints at its verdict here; a level expected above runs the hinted passes first, one expected
    below the hinted failures. Only the order changes: every verdict counted is a run's own."""
    lean: dict[tuple[float, ...], int] = {}
    for run in runs:
        k = min(range(len(coordinates)), key=lambda i: abs(coordinates[i] - run.point[along]))
        harder = k > j if falling else k < j
        if run.passed and harder:
            hint = 1
        elif not run.passed and not harder and k != j:
            hint = -1
        else:
            continue
        key = cells.key(run.point)
        lean[key] = lean.get(key, 0) + (hint if expect_above else -hint)
    return lean


def propose_pass_rate(space: Space, runs: Sequence[RateRun], along: int, rate: float, samples: int,
                      resolution: float, seed: int) -> RateProposal:
    """Up to ``samples`` points on the levels beside the guessed crossing, and the boundary estimated so far."""
    rng = random.Random(seed)
    cells = _Cells(space, along, rng)
    coordinates = _coordinates(space, along, resolution)
    levels = _levels(coordinates, runs, along, rate, cells.count)
    boundary = rate_boundary(space, runs, along, rate, resolution)
    split = _split(levels, rate)
    if boundary.located or split is None:
        return RateProposal((), boundary)
    t, falling = split
    taken: dict[int, set[tuple[float, ...]]] = {}
    for run in runs:
        index = min(range(len(coordinates)), key=lambda j: abs(coordinates[j] - run.point[along]))
        taken.setdefault(index, set()).add(cells.key(run.point))
    points: list[Point] = []
    for j, share in _shares(levels, t, falling, samples, rate, cells.count):
        lean = _lean(runs, coordinates, along, cells, j, falling, expect_above=(j < t) == falling)
        points += cells.fresh(coordinates[j], taken.get(j, set()), share, lean)
    return RateProposal(tuple(points), boundary)
