"""``fill-holes``: variants aimed at what the runs so far left empty.

Holes of the *inputs* are known exactly, because the variation chose the inputs: a listed value no run
used, a bucket of a drawn range no run fell in (the report's buckets, :mod:`~coverage_engine.coverage.input_domains`),
and, for every two varied parameters, a cell of their cross no run hit. Proposals are built greedily, as a
covering array is: each starts from the first hole still open, and the other axes take the cell that
closes the most holes besides (ties drawn from the seeded generator). A point falls at the centre of a
listed value's cell, and anywhere in a range bucket.

Holes of ``cover()`` items on *measured* values (a bucket of ``cover(gap, range: ..., every: ...)`` no
run landed in) cannot be aimed at: what a run measures is the scenario's business. The samples left go
there as a guess: near the inputs of the run whose measured value came closest to the hole.
"""

from __future__ import annotations

import itertools
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from coverage_engine.coverage.buckets import RangeBuckets
from coverage_engine.coverage.input_domains import RangeAxis, range_axis
from coverage_engine.coverage.run_records import ItemDecl
from coverage_engine.domains import InputDomain, numeric_value
from coverage_engine.search.estimate import HoleCount
from coverage_engine.search.space import Point, Space

#: How far (in the unit cube, per axis) a guess for a measured item's hole strays from the closest run.
GUESS_SPREAD = 0.05

#: A hole: one axis's cell ``((axis, cell),)`` or a cell of a cross of two axes ``((i, a), (j, b))``.
Hole = tuple[tuple[int, int], ...]


@dataclass(frozen=True)
class HoleProposal:
    points: tuple[Point, ...]
    holes: HoleCount
    done: bool
    guessed: tuple[str, ...] = ()       # the measured items' holes guessed at, as "item [bucket]"


class _Cells:
    """The cells of one axis: a listed axis's values, or the report's buckets of a range."""

    def __init__(self, space: Space, axis: int, declared: InputDomain | None) -> None:
        domain = space.axes[axis]
        self.levels = space.levels(axis)
        self.range: RangeAxis | None = None
        if self.levels is None:
            assert domain.low is not None and domain.high is not None
            bucketing = declared if declared is not None and declared.is_range else domain
            self.range = range_axis(bucketing)
            self.low, self.span = domain.low, domain.high - domain.low
        self.count = self.levels if self.levels is not None else self.range.count if self.range else 1

    def cell(self, u: float, value: object) -> int | None:
        if self.levels is not None:
            return min(int(u * self.levels), self.levels - 1)
        number = numeric_value(value)
        return None if number is None or self.range is None else self.range.index(number)

    def coordinate(self, cell: int, rng: random.Random) -> float:
        if self.levels is not None:
            return (cell + 0.5) / self.levels
        assert self.range is not None
        bucket = self.range.buckets()[cell]
        assert bucket.low is not None and bucket.high is not None
        if self.span <= 0:
            return 0.5
        low, high = (bucket.low - self.low) / self.span, (bucket.high - self.low) / self.span
        return min(1.0, max(0.0, low + rng.random() * (high - low)))


def input_holes(cells: Sequence[_Cells], hit: Sequence[Sequence[int]]) -> list[Hole]:
    """Every cell of one axis and of the cross of two axes that no run in ``hit`` (cells per run) holds."""
    singles = {((i, c),) for i, axis in enumerate(cells) for c in range(axis.count)}
    pairs = {((i, a), (j, b)) for i, j in itertools.combinations(range(len(cells)), 2)
             for a in range(cells[i].count) for b in range(cells[j].count)}
    for row in hit:
        for i, c in enumerate(row):
            singles.discard(((i, c),))
        for i, j in itertools.combinations(range(len(row)), 2):
            pairs.discard(((i, row[i]), (j, row[j])))
    return sorted(singles) + sorted(pairs)


def _closes(row: Sequence[int | None], holes: set[Hole]) -> int:
    return sum(1 for hole in holes if all(row[i] == c for i, c in hole))


def _fill(cells: Sequence[_Cells], holes: list[Hole], samples: int, rng: random.Random) -> list[list[int]]:
    """Rows of cells that close the holes, greedily, at most ``samples``."""
    open_holes = set(holes)
    rows: list[list[int]] = []
    while open_holes and len(rows) < samples:
        start = min(open_holes)
        row: list[int | None] = [None] * len(cells)
        for i, c in start:
            row[i] = c
        order = [i for i in range(len(cells)) if row[i] is None]
        rng.shuffle(order)
        for i in order:
            scores = []
            for c in range(cells[i].count):
                row[i] = c
                scores.append((_closes(row, {h for h in open_holes if any(a == i for a, _ in h)}), c))
            best = max(score for score, _ in scores)
            row[i] = rng.choice([c for score, c in scores if score == best])
        full = [c if c is not None else 0 for c in row]
        open_holes = {h for h in open_holes if not all(full[i] == c for i, c in h)}
        rows.append(full)
    return rows


def _measured_holes(decl: ItemDecl, runs: Sequence[tuple[Point, Sequence[object]]]) -> list[tuple[str, Point]]:
    """The empty buckets of a numeric ``cover()`` item with a range, each with the run that came closest."""
    if decl.range is None or decl.value_type is None or decl.value_type.kind not in ("int", "float"):
        return []
    buckets = RangeBuckets(decl.value_type.kind, decl.range[0], decl.range[1], decl.every)
    values = [(point, n) for point, samples in runs for n in map(numeric_value, samples) if n is not None]
    full = {buckets.key(n) for _, n in values}
    found = []
    for index, bucket in enumerate(buckets.buckets()):
        if index in full or not values or bucket.low is None or bucket.high is None:
            continue
        low, high = bucket.low, bucket.high
        point, _ = min(values, key=lambda pv: max(low - pv[1], pv[1] - high, 0.0))
        found.append((f"{decl.name} {bucket.label}", point))
    return found


def propose_holes(space: Space, points: Sequence[Point], assignments: Sequence[Mapping[str, object]],
                  samples: int, seed: int, declared: Mapping[str, InputDomain] | None = None,
                  measured: Sequence[tuple[ItemDecl, Sequence[tuple[Point, Sequence[object]]]]] = ()) \
        -> HoleProposal:
    """Up to ``samples`` points in the holes of the inputs (and guesses for measured items' holes)."""
    rng = random.Random(seed)
    cells = [_Cells(space, i, (declared or {}).get(axis.key)) for i, axis in enumerate(space.axes)]
    hit = []
    for point, assignment in zip(points, assignments, strict=True):
        row = [axis.cell(u, assignment.get(space.axes[i].key)) for i, (axis, u) in enumerate(zip(cells, point,
                                                                                              strict=True))]
        if all(c is not None for c in row):
            hit.append([c for c in row if c is not None])
    holes = input_holes(cells, hit)
    rows = _fill(cells, holes, samples, rng)
    chosen = [space.snap([cells[i].coordinate(c, rng) for i, c in enumerate(row)]) for row in rows]
    guesses = [hole for decl, runs in measured for hole in _measured_holes(decl, runs)]
    guessed = []
    for name, near in guesses[:max(0, samples - len(chosen))]:
        chosen.append(space.snap([u + rng.gauss(0.0, GUESS_SPREAD) for u in near]))
        guessed.append(name)
    closed = sum(1 for hole in holes if any(all(row[i] == c for i, c in hole) for row in rows))
    done = not holes and not guesses
    return HoleProposal(tuple(chosen), HoleCount(closed, len(guessed)), done, tuple(guessed))



