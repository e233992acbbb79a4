"""``boundary``: where pass turns to fail, located by bisecting between neighbouring runs that disagree.

Two runs *disagree* when one passed and the other failed (or, with ``--threshold``, a ``record()`` value
lies on either side of the threshold). A disagreeing pair is a *neighbour pair* when no other run lies
in the ball whose diameter is the segment between them (the Gabriel test): the boundary crosses that
segment and nothing run yet says where. Each round bisects the longest neighbour pairs (their midpoint,
snapped to a listed axis's value); a pair is *located* once it is no longer than ``--resolution`` along
every continuous axis (and neighbouring values along a listed one). In one dimension this is plain
bisection of the interval where the verdict flips.

When every neighbour pair is located (or none is seen yet) the samples left go where they tell the most:
before any run failed, points far from every run (a space-filling draw); after, points near the
located boundary in directions no run has gone yet, which the next round pairs and bisects.

Distances are taken in the unit cube (each range scaled to [0, 1]), so a resolution of 0.01 is 1 % of
every range. All draws come from a ``random.Random(seed)``: the same history, options and seed propose
the same points.
"""

from __future__ import annotations

import math
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from coverage_engine.search.estimate import MAX_BOUNDARY_VARIANTS, AxisBoundary, BoundaryEstimate
from coverage_engine.search.space import Point, Space, euclidean
from coverage_engine.search.surface import Surface, fit_surface

#: Candidate points drawn per proposal when space is filled or the boundary is explored.
CANDIDATES_PER_POINT = 32

#: A new point on a pair stays within the middle of it: between this fraction and one less it.
MIDDLE_PART = 0.1

#: Times a candidate is moved onto the estimated boundary (its nearest runs change as it moves).
SURFACE_STEPS = 3


@dataclass(frozen=True)
class Observation:
    """A run where it sits in the unit cube, which side of the boundary it is on, and its assignment."""

    point: Point
    failing: bool
    assignment: Mapping[str, object]


@dataclass(frozen=True)
class Pair:
    """Two neighbouring runs that disagree (indices into the observations) and the segment's length."""

    first: int
    second: int
    length: float
    located: bool


@dataclass(frozen=True)
class BoundaryProposal:
    points: tuple[Point, ...]
    estimate: BoundaryEstimate
    done: bool


def _located(space: Space, a: Point, b: Point, resolution: float) -> bool:
    for axis, (x, y) in enumerate(zip(a, b, strict=True)):
        levels = space.levels(axis)
        limit = resolution if levels is None else 1.0 / levels
        if abs(x - y) > limit * (1 + 1e-9) + 1e-12:
            return False
    return True


def neighbour_pairs(space: Space, observations: Sequence[Observation], resolution: float) -> list[Pair]:
    """The disagreeing neighbour pairs: each run with its nearest run of the other side, kept when no
    other run lies inside the ball on their segment (the Gabriel test), longest first."""
    points = [o.point for o in observations]
    pairs: dict[tuple[int, int], Pair] = {}
    for i, here in enumerate(observations):
        best, best_distance = -1, math.inf
        for j, there in enumerate(observations):
            if there.failing != here.failing:
                distance = euclidean(here.point, there.point)
                if distance < best_distance:
                    best, best_distance = j, distance
        if best < 0:
            continue
        key = (min(i, best), max(i, best))
        if key in pairs:
            continue
        a, b = points[key[0]], points[key[1]]
        middle = tuple((x + y) / 2 for x, y in zip(a, b, strict=True))
        radius = best_distance / 2 * (1 - 1e-9)
        if any(euclidean(p, middle) < radius for k, p in enumerate(points) if k not in key):
            continue
        pairs[key] = Pair(key[0], key[1], best_distance, _located(space, a, b, resolution))
    return sorted(pairs.values(), key=lambda p: (-p.length, p.first, p.second))


def _far_points(space: Space, taken: list[Point], count: int, rng: random.Random,
                surface: Sequence[Observation] = (), fitted: Surface | None = None, reach: float = math.inf) \
        -> list[Point]:
    """``count`` points, each as far as possible from every point taken so far (the best of a random
    draw). With ``surface`` (the runs), each candidate is first moved onto the boundary the runs estimate
    (the ``fitted`` surface where a candidate reaches it, else where the nearest failing and the nearest
    passing run are equally far: a nearest-neighbour classifier's surface), and candidates with a failing
    and a passing run within ``reach`` are preferred: there the estimate is bracketed by runs, so the points
    spread along the boundary where it is known instead of guessing where it is not."""
    chosen: list[Point] = []
    dims = len(space.axes)
    failing = [o.point for o in surface if o.failing]
    passing = [o.point for o in surface if not o.failing]
    for _ in range(count):
        best: Point | None = None
        best_score = -math.inf
        for _ in range(CANDIDATES_PER_POINT):
            candidate = space.snap([rng.random() for _ in range(dims)])
            score = 0.0
            if failing and passing:
                moved = fitted.onto(candidate) if fitted is not None else None
                candidate = space.snap(moved if moved is not None else _onto_surface(candidate, failing, passing))
                spread = max(euclidean(candidate, _nearest(candidate, failing)),
                             euclidean(candidate, _nearest(candidate, passing)))
                score = 0.0 if spread <= reach else -spread
            gap = min((euclidean(candidate, p) for p in taken + chosen), default=math.inf)
            if gap <= 0:
                continue
            score = score or gap
            if score > best_score:
                best, best_score = candidate, score
        if best is None:
            break
        chosen.append(best)
    return chosen


def _nearest(point: Sequence[float], among: Sequence[Point]) -> Point:
    return min(among, key=lambda p: euclidean(point, p))


def _onto_surface(point: Sequence[float], failing: Sequence[Point], passing: Sequence[Point]) -> list[float]:
    """``point`` moved onto the plane halfway between its nearest failing and nearest passing run
    (repeated a few times: the nearest runs change as it moves)."""
    here = list(point)
    for _ in range(SURFACE_STEPS):
        f, p = _nearest(here, failing), _nearest(here, passing)
        normal = [b - a for a, b in zip(f, p, strict=True)]
        size = sum(n * n for n in normal)
        if size == 0:
            break
        middle = [(a + b) / 2 for a, b in zip(f, p, strict=True)]
        offset = sum((x - m) * n for x, m, n in zip(here, middle, normal, strict=True)) / size
        here = [x - offset * n for x, n in zip(here, normal, strict=True)]
    return here


def _shares(pairs: Sequence[Pair], samples: int, dims: int) -> list[int]:
    """How many points each unlocated pair gets: one each, longest first; in one dimension the samples left
    are shared out too (there is no "along the boundary" to spread them to), longest pairs first."""
    open_pairs = [i for i, pair in enumerate(pairs) if not pair.located]
    shares = [0] * len(pairs)
    for i in open_pairs[:samples]:
        shares[i] = 1
    left = samples - min(samples, len(open_pairs))
    while dims == 1 and open_pairs and left > 0:
        for i in open_pairs:
            if left == 0:
                break
            shares[i] += 1
            left -= 1
    return shares


def _bisections(space: Space, observations: Sequence[Observation], pairs: Sequence[Pair], samples: int,
                resolution: float, surface: Surface | None) -> list[Point]:
    """Points on the longest unlocated pairs, at most ``samples``, none within half the resolution of another
    proposal or of a run. A pair given one point gets it where the fitted surface crosses it, kept away from
    its ends (so every pair shrinks whatever the fit says), else at its middle; one given ``m`` points (in one
    dimension) gets them evenly spaced, cutting it into ``m + 1`` parts."""
    taken = [o.point for o in observations]
    chosen: list[Point] = []
    for pair, share in zip(pairs, _shares(pairs, samples, len(space.axes)), strict=True):
        if not share:
            continue
        a, b = observations[pair.first].point, observations[pair.second].point
        if share == 1:
            t = surface.crossing(a, b) if surface is not None else None
            spots = [0.5 if t is None else min(1 - MIDDLE_PART, max(MIDDLE_PART, t))]
        else:
            spots = [j / (share + 1) for j in range(1, share + 1)]
        for t in spots:
            point = space.snap([x + t * (y - x) for x, y in zip(a, b, strict=True)])
            if point in taken or any(euclidean(point, c) < resolution / 2 for c in chosen):
                continue
            chosen.append(point)
    return chosen


def _one_dimensional(space: Space, observations: Sequence[Observation]) -> AxisBoundary | None:
    """The flip of a single varied axis: where it is, ± half the gap between the runs around it
    (None when the space has several axes or the verdict flips more than once, or never)."""
    if len(space.axes) != 1 or space.axes[0].values is not None:
        return None
    ordered = sorted(observations, key=lambda o: o.point[0])
    flips = [(a, b) for a, b in zip(ordered, ordered[1:], strict=False) if a.failing != b.failing]
    if len(flips) != 1:
        return None
    a, b = flips[0]
    axis = space.axes[0]
    low = space.value_at(0, a.point[0])
    high = space.value_at(0, b.point[0])
    assert isinstance(low, float) and isinstance(high, float)
    return AxisBoundary((low + high) / 2, abs(high - low) / 2, axis.unit)


def _boundary_variants(observations: Sequence[Observation], pairs: Sequence[Pair]) -> tuple[Mapping[str, object], ...]:
    seen: dict[int, None] = {}
    for pair in pairs:
        if pair.located:
            seen.setdefault(pair.first)
            seen.setdefault(pair.second)
    return tuple(observations[i].assignment for i in list(seen)[:MAX_BOUNDARY_VARIANTS])


def propose_boundary(space: Space, observations: Sequence[Observation], samples: int, resolution: float,
                     seed: int) -> BoundaryProposal:
    """Up to ``samples`` points that locate the boundary further, and the boundary estimated so far."""
    rng = random.Random(seed)
    pairs = neighbour_pairs(space, observations, resolution)
    taken = [o.point for o in observations]
    fitted = fit_surface([o.point for o in observations], [o.failing for o in observations])
    points = _bisections(space, observations, pairs, samples, resolution, fitted)
    done = bool(pairs) and all(pair.located for pair in pairs)
    one = _one_dimensional(space, observations)
    if not (done and len(space.axes) == 1):        # a located flip in one dimension needs nothing more
        lengths = sorted(pair.length for pair in pairs)
        reach = lengths[len(lengths) // 2] if lengths else math.inf
        points += _far_points(space, taken + points, samples - len(points), rng, observations if pairs else (),
                              fitted, reach)
    axes = {space.axes[0].key: one} if one is not None else {}
    estimate = BoundaryEstimate(axes, _boundary_variants(observations, pairs), len(pairs),
                                sum(1 for pair in pairs if pair.located))
    return BoundaryProposal(tuple(points), estimate, done)
