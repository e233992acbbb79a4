"""Which combinations to write: the full product, a t-way covering array, or a seeded sample.

``full`` (default) keeps the plan's product. The others set :attr:`VariationPlan.rows`:

- ``pairwise`` / ``t-way --strength t``: a covering array in which every t-tuple of values (of any t
  dimensions) that some valid variant can hold appears in at least one row. Built here by a greedy,
  AETG-style generator: each new row starts from an uncovered tuple and fills the other dimensions,
  one at a time in a random order, with the value that covers the most still-uncovered tuples
  (ties broken by the seeded random generator). Values that do not resolve are never chosen, and a
  tuple holding one is reported as impossible rather than uncovered.
- ``random``, ``lhs`` (Latin hypercube), ``halton``, ``sobol``: ``--samples N`` points of the unit
  cube, one coordinate per dimension; a discrete dimension (list, integer or stepped range, the
  parameter documents) maps a coordinate ``u`` to its value ``floor(u * k)``; a continuous range maps it
  to ``low + u * (high - low)``. ``random``, ``lhs`` and ``halton`` are written here (Halton with a
  seeded random shift); ``sobol`` uses ``scipy.stats.qmc`` (the optional ``sampling`` extra), imported
  only when asked for.

Everything is a function of the file, the options and the seed, so the same inputs give the same
variants byte for byte. Continuous ranges are drawn *before* the values are checked (each drawn value
becomes a choice of its dimension, so it is checked like a listed one), covering arrays are built
*after* (so they avoid values that do not resolve).
"""

from __future__ import annotations

import itertools
import math
import random
from collections.abc import Sequence
from dataclasses import dataclass, replace

from coverage_engine.errors import OscError, ResolveError
from coverage_engine.variation.dimensions import Choice, Dimension
from coverage_engine.variation.plan import VariationPlan, _slots
from coverage_engine.variation.template import TextTemplate

STRATEGIES = ("full", "pairwise", "t-way", "random", "lhs", "halton", "sobol")
SAMPLERS = ("random", "lhs", "halton", "sobol")
COVERING = ("pairwise", "t-way")
#: Candidate rows tried per row of a covering array (more: fewer rows, more time).
CANDIDATES = 8


class StrategyError(OscError):
    """A strategy that cannot be applied to this file with these options."""


@dataclass(frozen=True)
class StrategyOptions:
    """``--strategy``, ``--strength``, ``--samples`` and ``--seed`` (a seed is always set by the caller)."""

    strategy: str = "full"
    strength: int = 2
    samples: int | None = None
    seed: int = 0

    @property
    def t(self) -> int:
        return 2 if self.strategy == "pairwise" else self.strength


def draw_continuous(plan: VariationPlan, options: StrategyOptions) -> None:
    """Before the values are checked: refuse continuous ranges without a sampler, or draw the sample.

    For a sampler, every dimension gets its coordinate of each of the ``samples`` points; a continuous
    range's drawn values become its choices (in draw order), and ``plan.rows`` the points.
    """
    continuous = [d for d in plan.dimensions if d.continuous is not None]
    if options.strategy not in SAMPLERS:
        if continuous:
            dim = continuous[0]
            assert dim.continuous is not None
            raise StrategyError(
                f"'{dim.key}' is a continuous range ({dim.continuous.text(dim.continuous.low)}.."
                f"{dim.continuous.text(dim.continuous.high)}): --strategy {options.strategy} needs listed values",
                dim.continuous.location,
                hint="draw values with --strategy lhs|random|sobol|halton --samples N, or give the range a step: "
                     "range(low, high, step)")
        return
    if options.samples is None:
        raise StrategyError(f"--strategy {options.strategy} needs --samples N (how many variants to draw)")
    sizes = plan.sizes                     # choices per axis: the dimensions, then the documents if any
    points = unit_points(options.strategy, options.samples, len(sizes), options.seed)
    dimensions: list[Dimension] = list(plan.dimensions)
    rows = [[0] * len(sizes) for _ in points]
    for axis, size in enumerate(sizes):
        spec = dimensions[axis].continuous if axis < len(dimensions) else None
        if spec is not None:                # each point draws its own value: row i takes choice i
            values = [spec.low + p[axis] * (spec.high - spec.low) for p in points]
            dimensions[axis] = replace(dimensions[axis],
                                       choices=tuple(Choice(spec.text(v), v, spec.location) for v in values))
            for i, row in enumerate(rows):
                row[axis] = i
        else:                               # a discrete axis: the coordinate picks one of its values
            for row, point in zip(rows, points, strict=True):
                row[axis] = min(int(point[axis] * size), size - 1)
    plan.dimensions = dimensions
    plan.template = TextTemplate.build(plan.text, dimensions)
    plan.slots = _slots(dimensions, plan.documents)
    plan._bad = [set() for _ in plan.slots]
    plan.rows = [tuple(r) for r in rows]


def unit_points(strategy: str, count: int, axes: int, seed: int) -> list[list[float]]:
    """``count`` points of ``[0, 1)^axes`` by ``strategy`` (deterministic in ``seed``)."""
    rng = random.Random(seed)
    if strategy == "random":
        return [[rng.random() for _ in range(axes)] for _ in range(count)]
    if strategy == "lhs":
        columns = []
        for _ in range(axes):
            strata = list(range(count))
            rng.shuffle(strata)
            columns.append([(s + rng.random()) / count for s in strata])
        return [[columns[a][i] for a in range(axes)] for i in range(count)]
    if strategy == "halton":
        shift = [rng.random() for _ in range(axes)]
        primes = _primes(axes)
        return [[(_radical_inverse(i + 1, primes[a]) + shift[a]) % 1.0 for a in range(axes)] for i in range(count)]
    if strategy == "sobol":
        try:
            from scipy.stats import qmc  # type: ignore[import-untyped, unused-ignore]
        except ImportError:
            raise StrategyError("--strategy sobol needs scipy: pip install 'scenario-coverage[sampling]'") from None
        sampler = qmc.Sobol(d=max(axes, 1), scramble=True, seed=seed)
        return [list(map(float, p[:axes])) for p in sampler.random(count)]
    raise StrategyError(f"unknown sampling strategy '{strategy}'")


def _primes(count: int) -> list[int]:
    primes: list[int] = []
    candidate = 2
    while len(primes) < count:
        if all(candidate % p for p in primes if p * p <= candidate):
            primes.append(candidate)
        candidate += 1
    return primes


def _radical_inverse(index: int, base: int) -> float:
    result, fraction = 0.0, 1.0 / base
    while index:
        index, digit = divmod(index, base)
        result += digit * fraction
        fraction /= base
    return result


@dataclass(frozen=True)
class TupleCoverage:
    """What a covering array covers: t, the t-tuples covered, those some valid variant can hold, the impossible."""

    strength: int
    covered: int
    coverable: int
    impossible: int


def build_covering_array(plan: VariationPlan, options: StrategyOptions) -> TupleCoverage:
    """After the values are checked: choose rows covering every coverable t-tuple; sets ``plan.rows``."""
    sizes = plan.sizes
    t = options.t
    if t < 2:
        raise StrategyError("--strength must be 2 or more (2 is pairwise)")
    if t > len(sizes):
        raise StrategyError(f"--strength {t} needs at least {t} varied dimensions (this file has {len(sizes)})")
    bad = _bad_values(plan)
    allowed = [[v for v in range(n) if v not in bad[a]] for a, n in enumerate(sizes)]
    if any(not values for values in allowed):
        raise ResolveError("no value of one dimension resolves: nothing to cover")
    rng = random.Random(options.seed)
    groups = list(itertools.combinations(range(len(sizes)), t))
    uncovered: dict[tuple[int, ...], set[tuple[int, ...]]] = {
        g: set(itertools.product(*(allowed[a] for a in g))) for g in groups}
    impossible = sum(math.prod(sizes[a] for a in g) for g in groups) - sum(len(u) for u in uncovered.values())
    coverable = sum(len(u) for u in uncovered.values())
    by_axis: dict[int, list[tuple[int, ...]]] = {a: [g for g in groups if a in g] for a in range(len(sizes))}
    # How many uncovered tuples each (axis, value) still takes part in: the tie-breaker of the greedy choice
    # (a value that many open tuples need is better placed now than later).
    pending: list[list[int]] = [[0] * n for n in sizes]
    for g, open_tuples in uncovered.items():
        for values in open_tuples:
            for a, v in zip(g, values, strict=True):
                pending[a][v] += 1
    rows: list[tuple[int, ...]] = []
    remaining = coverable
    while remaining:
        best_row: list[int] | None = None
        best_gain = -1
        for _ in range(CANDIDATES):
            row, gain = _candidate(uncovered, groups, allowed, by_axis, rng, len(sizes), pending)
            if gain > best_gain:
                best_row, best_gain = row, gain
        assert best_row is not None and best_gain > 0
        for g in groups:
            key = tuple(best_row[a] for a in g)
            if key in uncovered[g]:
                uncovered[g].discard(key)
                remaining -= 1
                for a, v in zip(g, key, strict=True):
                    pending[a][v] -= 1
        rows.append(tuple(best_row))
    plan.rows = _drop_redundant(rows, groups)
    return TupleCoverage(t, coverable, coverable, impossible)


def _candidate(uncovered: dict[tuple[int, ...], set[tuple[int, ...]]], groups: Sequence[tuple[int, ...]],
               allowed: list[list[int]], by_axis: dict[int, list[tuple[int, ...]]], rng: random.Random,
               axes: int, pending: list[list[int]]) -> tuple[list[int], int]:
    """One greedy row: seeded by an uncovered tuple, then each other axis (random order) at its best value."""
    open_groups = [g for g in groups if uncovered[g]]
    group = rng.choice(open_groups)
    # Seed with the open tuple of that group whose values the most open tuples still need.
    seed_tuple = max(sorted(uncovered[group]),
                     key=lambda values: sum(pending[a][v] for a, v in zip(group, values, strict=True)))
    row: list[int | None] = [None] * axes
    for a, v in zip(group, seed_tuple, strict=True):
        row[a] = v
    order = [a for a in range(axes) if row[a] is None]
    rng.shuffle(order)
    filled = set(group)
    for axis in order:
        # Only groups whose other axes already hold a value can gain from this axis's choice.
        ready = [(g, uncovered[g], g.index(axis)) for g in by_axis[axis]
                 if uncovered[g] and all(a in filled for a in g if a != axis)]
        best_value, best_score = allowed[axis][0], (-1, -1)
        values = list(allowed[axis])
        rng.shuffle(values)
        weights = pending[axis]
        for value in values:
            row[axis] = value
            gained = 0
            for g, open_tuples, _ in ready:
                if tuple(row[a] for a in g) in open_tuples:
                    gained += 1
            score = (gained, weights[value])
            if score > best_score:
                best_value, best_score = value, score
        row[axis] = best_value
        filled.add(axis)
    full = [v if v is not None else 0 for v in row]
    gain = sum(1 for g in groups if tuple(full[a] for a in g) in uncovered[g])
    return full, gain


def _drop_redundant(rows: list[tuple[int, ...]], groups: Sequence[tuple[int, ...]]) -> list[tuple[int, ...]]:
    """Remove rows every tuple of which other rows also cover (latest rows first: they covered least)."""
    counts: dict[tuple[tuple[int, ...], tuple[int, ...]], int] = {}
    for row in rows:
        for g in groups:
            key = (g, tuple(row[a] for a in g))
            counts[key] = counts.get(key, 0) + 1
    kept = []
    for row in reversed(rows):
        keys = [(g, tuple(row[a] for a in g)) for g in groups]
        if all(counts[k] > 1 for k in keys):
            for k in keys:
                counts[k] -= 1
            continue
        kept.append(row)
    kept.reverse()
    return kept


def _bad_values(plan: VariationPlan) -> list[set[int]]:
    """Per axis, the values that never resolve (from single-dimension slots; joint slots are left to rejection)."""
    bad: list[set[int]] = [set() for _ in plan.sizes]
    for slot, options in zip(plan.slots, plan.bad_options(), strict=True):
        if len(slot.dims) == 1:
            bad[slot.dims[0]] = set(options)
    return bad

