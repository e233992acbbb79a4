"""Stage 4 of a covering-array strategy: choose rows in which every coverable t-tuple of values appears.

``pairwise`` / ``t-way --strength t`` cover every t-tuple of values (of any t dimensions) that some
valid variant can hold in at least one row. Built here by a greedy, AETG-style generator: each new row
starts from an uncovered tuple and fills the other dimensions, one at a time in a random order, with
the value that covers the most still-uncovered tuples (ties broken by the seeded random generator).
Values that do not resolve are never chosen, and a tuple holding one is reported as impossible rather
than uncovered. Pairwise over many values is built by IPOG instead (:mod:`coverage_engine.variation.ipog`,
linear in its rows); an array beyond ``--max-variants`` or the tuples a builder can hold is refused
before it is built (:mod:`coverage_engine.variation.covering_size`).
"""

from __future__ import annotations

import itertools
import math
import random
from collections.abc import Sequence
from dataclasses import dataclass

from coverage_engine.errors import ResolveError
from coverage_engine.location import Location
from coverage_engine.variation import covering_size
from coverage_engine.variation.conditions import ConstraintTables
from coverage_engine.variation.ipog import ipog_pairwise
from coverage_engine.variation.pairwise import pairwise_rows
from coverage_engine.variation.plan import CheckedVariation, ParsedVariation, VariationPlan, advance
from coverage_engine.variation.strategies import StrategyError, StrategyOptions, Tick

#: Candidate rows tried per row of a covering array (more: fewer rows, more time).
CANDIDATES = 8

#: Above this estimate of its work (least rows x dimensions² x values) the AETG pairwise builder, which
#: compacts its rows in rows² time, gives way to IPOG (linear in the rows: 10 x 50 values in 1.5 s).
AETG_WORK = 5_000_000


@dataclass(frozen=True)
class TupleCoverage:
    """What a covering array covers: t, the t-tuples covered, those some valid variant can hold, the impossible."""

    strength: int
    covered: int
    coverable: int
    impossible: int


def refuse_oversized(parsed: ParsedVariation, options: StrategyOptions, limit: int | None,
                     sizes: Sequence[int] | None = None,
                     constrained: bool = False) -> covering_size.CoveringEstimate:
    """:class:`StrategyError` when the covering array of ``parsed`` (its dimensions of ``sizes`` values;
    default: all of them, before any is checked; ``constrained``: keep conditions restrict the tuples)
    would be beyond ``limit`` or the builder's memory."""
    found = covering_size.estimate(parsed.sizes if sizes is None else sizes, options.t)
    tracks_tuples = options.t > 2 or constrained
    refused = covering_size.refusal(found, limit, tracks_tuples) if limit else None
    if refused is not None:
        raise StrategyError(refused, Location.whole_file(str(parsed.path)),
                            hint=covering_size.alternatives(found, limit or 0))
    return found


def choose_covering(checked: CheckedVariation, options: StrategyOptions,
                    seeds: Sequence[tuple[int, ...]] = (), *, limit: int | None = None,
                    tick: Tick | None = None) -> tuple[VariationPlan, TupleCoverage]:
    """After the values are checked: the plan of rows covering every coverable t-tuple, and what they cover.

    ``seeds`` are rows written before (``--only-new``): the tuples they cover count as covered, and
    only the rows still needed are chosen (a ``t-way --strength 3`` run after a pairwise one adds
    rows for the triples the pairwise rows miss). An array that needs more rows than ``limit``
    (``--max-variants``), or more tuples than the builder can hold, is refused before it is built
    (:mod:`coverage_engine.variation.covering_size`); ``tick(done, total)`` reports progress.
    """
    sizes = checked.sizes
    t = options.t
    if t < 2:
        raise StrategyError("--strength must be 2 or more (2 is pairwise)")
    if t > len(sizes):
        raise StrategyError(f"--strength {t} needs at least {t} varied dimensions (this file has {len(sizes)})")
    bad = _bad_values(checked)
    allowed = [[v for v in range(n) if v not in bad[a]] for a, n in enumerate(sizes)]
    if any(not values for values in allowed):
        raise ResolveError("no value of one dimension resolves: nothing to cover")
    rng = random.Random(options.seed)
    tables = checked.constraints
    found = refuse_oversized(checked, options, limit, [len(values) for values in allowed], tables is not None)
    if t == 2 and tables is None:          # the common case has fast builders of its own
        pairs = sum(len(allowed[a]) * len(allowed[b]) for a, b in itertools.combinations(range(len(sizes)), 2))
        every = sum(sizes[a] * sizes[b] for a, b in itertools.combinations(range(len(sizes)), 2))
        many = found.least_rows * len(sizes) ** 2 * max(sizes) > AETG_WORK
        rows = (ipog_pairwise(sizes, allowed, rng, seeds, tick) if many
                else pairwise_rows(sizes, allowed, rng, seeds))
        return advance(checked, VariationPlan, rows=tuple(rows)), TupleCoverage(2, pairs, pairs, every - pairs)
    rows, coverage = _greedy_rows(sizes, allowed, t, tables, seeds, rng, tick)
    return advance(checked, VariationPlan, rows=tuple(rows)), coverage


def _greedy_rows(sizes: Sequence[int], allowed: list[list[int]], t: int, tables: ConstraintTables | None,
                 seeds: Sequence[tuple[int, ...]], rng: random.Random,
                 tick: Tick | None) -> tuple[list[tuple[int, ...]], TupleCoverage]:
    """The AETG-style rows of the module docstring, and the tuples they cover."""
    groups = list(itertools.combinations(range(len(sizes)), t))
    uncovered: dict[tuple[int, ...], set[tuple[int, ...]]] = {
        g: {values for values in itertools.product(*(allowed[a] for a in g))
            if tables is None or tables.tuple_allowed(g, values)} for g in groups}
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
    for seed_row in seeds:
        remaining -= _cover(seed_row, groups, uncovered, pending)
    while remaining:
        best_row: list[int] | None = None
        best_gain = -1
        for _ in range(CANDIDATES):
            row, gain, seed = _candidate(uncovered, groups, allowed, by_axis, rng, len(sizes), pending, tables)
            if row is None:
                # No valid row holds this tuple although no condition forbids it alone: it is impossible.
                group, values = seed
                uncovered[group].discard(values)
                remaining -= 1
                coverable -= 1
                impossible += 1
                for a, v in zip(group, values, strict=True):
                    pending[a][v] -= 1
                if not remaining:
                    break
                continue
            if gain > best_gain:
                best_row, best_gain = row, gain
        if best_row is None:
            continue
        assert best_gain > 0
        remaining -= _cover(best_row, groups, uncovered, pending)
        rows.append(tuple(best_row))
        if tick is not None:
            tick(coverable - remaining, coverable)
    return _drop_redundant(rows, groups), TupleCoverage(t, coverable, coverable, impossible)


def _cover(row: Sequence[int], groups: Sequence[tuple[int, ...]],
           uncovered: dict[tuple[int, ...], set[tuple[int, ...]]], pending: list[list[int]]) -> int:
    """Mark the t-tuples ``row`` holds covered; returns how many were still open."""
    taken = 0
    for g in groups:
        key = tuple(row[a] for a in g)
        if key in uncovered[g]:
            uncovered[g].discard(key)
            taken += 1
            for a, v in zip(g, key, strict=True):
                pending[a][v] -= 1
    return taken


def _candidate(uncovered: dict[tuple[int, ...], set[tuple[int, ...]]], groups: Sequence[tuple[int, ...]],
               allowed: list[list[int]], by_axis: dict[int, list[tuple[int, ...]]], rng: random.Random,
               axes: int, pending: list[list[int]], tables: ConstraintTables | None = None,
               ) -> tuple[list[int] | None, int, tuple[tuple[int, ...], tuple[int, ...]]]:
    """One greedy row: seeded by an uncovered tuple, then each other axis (random order) at its best value.

    With keep conditions, a value that would break one (given the axes already filled) is never
    chosen; when some axis has no such value left the row is None (the seed tuple cannot be completed).
    Returns the row, the tuples it newly covers, and the seed ``(group, values)``.
    """
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
        best_value, best_score = None, (-1, -1)
        values = list(allowed[axis])
        rng.shuffle(values)
        weights = pending[axis]
        for value in values:
            row[axis] = value
            if tables is not None and not tables.partial_allowed(row):
                continue
            gained = 0
            for g, open_tuples, _ in ready:
                if tuple(row[a] for a in g) in open_tuples:
                    gained += 1
            score = (gained, weights[value])
            if score > best_score:
                best_value, best_score = value, score
        if best_value is None:      # the greedy choices led to a dead end: look for any valid row
            found = _complete(group, seed_tuple, allowed, tables, axes) if tables is not None else None
            if found is None:
                return None, 0, (group, seed_tuple)
            row = list(found)
            break
        row[axis] = best_value
        filled.add(axis)
    full = [v if v is not None else 0 for v in row]
    if tables is not None and tables.violated(full) is not None:
        found = _complete(group, seed_tuple, allowed, tables, axes)
        if found is None:
            return None, 0, (group, seed_tuple)
        full = found
    gain = sum(1 for g in groups if tuple(full[a] for a in g) in uncovered[g])
    return full, gain, (group, seed_tuple)


#: Most partial rows tried when looking for a valid row that holds a given tuple.
COMPLETION_BUDGET = 100_000


def _complete(group: tuple[int, ...], values: tuple[int, ...], allowed: list[list[int]],
              tables: ConstraintTables, axes: int) -> list[int] | None:
    """A row holding ``values`` on ``group`` that breaks no keep condition (depth first), or None."""
    row: list[int | None] = [None] * axes
    for a, v in zip(group, values, strict=True):
        row[a] = v
    if not tables.partial_allowed(row):
        return None
    free = [a for a in range(axes) if row[a] is None]
    budget = [COMPLETION_BUDGET]

    def search(position: int) -> bool:
        if position == len(free):
            return tables.violated([v if v is not None else 0 for v in row]) is None
        axis = free[position]
        for value in allowed[axis]:
            budget[0] -= 1
            if budget[0] < 0:
                return False
            row[axis] = value
            if tables.partial_allowed(row) and search(position + 1):
                return True
        row[axis] = None
        return False

    return [v if v is not None else 0 for v in row] if search(0) else None


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


def _bad_values(plan: CheckedVariation) -> list[set[int]]:
    """Per axis, the values that never resolve (from single-dimension slots; joint slots are left to rejection)."""
    bad: list[set[int]] = [set() for _ in plan.sizes]
    for slot, options in zip(plan.slots, plan.bad_options(), strict=True):
        if len(slot.dims) == 1:
            bad[slot.dims[0]] = set(options)
    return bad

