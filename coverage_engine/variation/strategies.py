"""Which combinations to write: the full product, a t-way covering array, or a seeded sample.

``full`` (default) keeps the plan's product. The others set :attr:`VariationPlan.rows`:

- ``pairwise`` / ``t-way --strength t``: a covering array in which every t-tuple of values (of any t
  dimensions) that some valid variant can hold appears in at least one row. Built here by a greedy,
  AETG-style generator: each new row starts from an uncovered tuple and fills the other dimensions,
  one at a time in a random order, with the value that covers the most still-uncovered tuples
  (ties broken by the seeded random generator). Values that do not resolve are never chosen, and a
  tuple holding one is reported as impossible rather than uncovered. Pairwise over many values is
  built by IPOG instead (:mod:`coverage_engine.variation.ipog`, linear in its rows); an array beyond
  ``--max-variants`` or the tuples a builder can hold is refused before it is built
  (:mod:`coverage_engine.variation.covering_size`).
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
import json
import math
import random
import warnings
from array import array
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace

from coverage_engine.errors import OscError, ResolveError
from coverage_engine.location import Location
from coverage_engine.variation import covering_size
from coverage_engine.variation.conditions import ConstraintTables
from coverage_engine.variation.dimensions import Dimension
from coverage_engine.variation.drawn import DrawnChoices
from coverage_engine.variation.ipog import ipog_pairwise
from coverage_engine.variation.pairwise import pairwise_rows
from coverage_engine.variation.plan import VariationPlan, _slots
from coverage_engine.variation.template import TextTemplate

STRATEGIES = ("full", "pairwise", "t-way", "random", "lhs", "halton", "sobol")
SAMPLERS = ("random", "lhs", "halton", "sobol")
COVERING = ("pairwise", "t-way")
#: Candidate rows tried per row of a covering array (more: fewer rows, more time).
CANDIDATES = 8


#: Progress of a long computation: ``tick(done, total)``.
Tick = Callable[[int, int], None]

#: Above this estimate of its work (least rows x dimensions² x values) the AETG pairwise builder, which
#: compacts its rows in rows² time, gives way to IPOG (linear in the rows: 10 x 50 values in 1.5 s).
AETG_WORK = 5_000_000


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
    if not plan.sizes:        # every point would be the same variant: N copies of the scenario
        raise StrategyError(f"--strategy {options.strategy} draws points over the varied parameters, and "
                            f"{plan.path.name} varies none; nothing to draw", Location(str(plan.path), 0, 0),
                            hint="vary a parameter (keep(it.x in [...]) or a range), or run the scenario as it is")
    sizes = plan.sizes                     # choices per axis: the dimensions, then the documents if any
    columns = unit_columns(options.strategy, options.samples, len(sizes), options.seed)
    count = len(columns[0]) if columns else options.samples
    dimensions: list[Dimension] = list(plan.dimensions)
    choices: list[Sequence[int]] = []
    for axis, (size, column) in enumerate(zip(sizes, columns, strict=True)):
        spec = dimensions[axis].continuous if axis < len(dimensions) else None
        if spec is not None:                # each point draws its own value: row i takes choice i
            low, span = spec.low, spec.high - spec.low
            values = array("d", [low + p * span for p in column])
            dimensions[axis] = replace(dimensions[axis], choices=DrawnChoices(values, spec))
            choices.append(range(count))
        else:                               # a discrete axis: the coordinate picks one of its values
            last = size - 1
            choices.append([min(int(p * size), last) for p in column])
    plan.dimensions = dimensions
    plan.template = TextTemplate.build(plan.text, dimensions)
    plan.slots = _slots(dimensions, plan.documents)
    plan._bad = [set() for _ in plan.slots]
    plan.rows = list(zip(*choices, strict=True)) if choices else [()] * count


def check_continuable(options: StrategyOptions, held: int, runs: Sequence[dict], where: Location) -> None:
    """``--only-new``: refuse a Latin hypercube that would be added to ``held`` variants of another design.

    ``random``, ``halton`` and ``sobol`` continue by themselves (their first N points do not depend on
    how many are drawn, so the points already written are found in the store and passed over). A Latin
    hypercube of N points puts one point in each N-th of every range: the points of an earlier, smaller
    one are no part of it, so no set of new points turns the earlier files into a larger hypercube.
    The same design again (same seed and count) is accepted: it writes nothing new.
    """
    if options.strategy != "lhs" or not held:
        return
    last = runs[-1] if runs else {}
    if last.get("strategy") == "lhs" and last.get("seed") == options.seed and last.get("samples") == options.samples:
        return
    before = f"--strategy {last.get('strategy')}, --samples {last.get('samples')}" if last else "another design"
    raise StrategyError(
        f"--strategy lhs --samples {options.samples} --only-new cannot add to the {held} variant(s) earlier runs "
        f"wrote ({before}): a Latin hypercube of {options.samples} points has one point in each "
        f"1/{options.samples} of every range, and the points already written are no part of such a design, so "
        "new points cannot complete it (the union would crowd some strata and leave others empty)", where,
        hint="grow a sample run by run with --strategy sobol, halton or random and --only-new (they continue "
             "their sequence), or draw the larger hypercube afresh without --only-new (it replaces the earlier "
             "files)")


def rows_of(plan: VariationPlan, assignments: Iterable[str]) -> list[tuple[int, ...]]:
    """The rows (choice per axis) of stored assignments that this plan can express (others are left out)."""
    lookup = [{json.dumps(value): i for i, value in enumerate(values)} for values in plan.stored()]
    keys = plan.keys
    rows = []
    for text in assignments:
        try:
            assignment = json.loads(text)
        except ValueError:
            continue
        row = []
        for key, table in zip(keys, lookup, strict=True):
            choice = table.get(json.dumps(assignment.get(key))) if key in assignment else None
            if choice is None:
                break
            row.append(choice)
        else:
            rows.append(tuple(row))
    return sorted(rows)


def describe_options(options: StrategyOptions) -> str | None:
    """``strategy lhs, samples 200, seed 7`` (None for the full product, which needs no seed)."""
    if options.strategy == "full":
        return None
    parts = [f"strategy {options.strategy}"]
    if options.strategy in COVERING:
        parts.append(f"strength {options.t}")
    if options.strategy in SAMPLERS:
        parts.append(f"samples {options.samples}")
    return ", ".join([*parts, f"seed {options.seed}"])


#: A sampler whose draws keep conditions reject draws up to this many times the samples asked for.
MAX_OVERSAMPLING = 64


def oversampled(options: StrategyOptions, factor: int) -> StrategyOptions:
    """``options`` drawing ``factor`` times the samples (a sampler redrawing after rejections)."""
    if factor == 1 or options.strategy not in SAMPLERS or options.samples is None:
        return options
    return replace(options, samples=options.samples * factor)


def enough_samples(plan: VariationPlan, options: StrategyOptions, factor: int) -> bool:
    """After the keep conditions left out some draws: keep the first ``samples`` rows, or ask for more.

    True when the plan is final (not a sampler, nothing left out, or enough rows kept: the first
    ``samples`` are kept, in draw order). False when a larger draw should be tried. When even
    :data:`MAX_OVERSAMPLING` times the samples do not give enough, the condition that left out the
    most draws is named in a :class:`StrategyError`.
    """
    if options.strategy not in SAMPLERS or options.samples is None or plan.rows is None:
        return True
    if len(plan.rows) >= options.samples:
        plan.rows = plan.rows[:options.samples]
        return True
    if factor < MAX_OVERSAMPLING:
        return False
    worst = max(plan.excluded_by.items(), key=lambda item: item[1])
    where = next((c.location for c in plan.constraints.conditions if c.text == worst[0]), None) \
        if plan.constraints is not None else None
    raise StrategyError(
        f"only {len(plan.rows)} of {options.samples * factor} drawn variants satisfy the keep conditions "
        f"({worst[0]} left out {worst[1]}); --samples {options.samples} cannot be reached", where,
        hint="widen the ranges, loosen the condition, or ask for fewer --samples")


def unit_columns(strategy: str, count: int, axes: int, seed: int) -> list[list[float]]:
    """``count`` points of ``[0, 1)^axes`` by ``strategy`` (deterministic in ``seed``), one list per axis."""
    rng = random.Random(seed)
    if strategy == "random":                # drawn point by point: axis a of point i is draw i * axes + a
        draws = [rng.random() for _ in range(count * axes)]
        return [draws[a::axes] for a in range(axes)]
    if strategy == "lhs":
        columns: list[list[float]] = []
        for _ in range(axes):
            strata = list(range(count))
            rng.shuffle(strata)
            columns.append([(s + rng.random()) / count for s in strata])
        return columns
    if strategy == "halton":
        shift = [rng.random() for _ in range(axes)]
        primes = _primes(axes)
        return [[(_radical_inverse(i + 1, primes[a]) + shift[a]) % 1.0 for i in range(count)] for a in range(axes)]
    if strategy == "sobol":
        try:
            from scipy.stats import qmc  # type: ignore[import-untyped, unused-ignore]
        except ImportError:
            raise StrategyError("--strategy sobol needs scipy: pip install 'scenario-coverage[sampling]'") from None
        sampler = qmc.Sobol(d=max(axes, 1), scramble=True, seed=seed)
        with warnings.catch_warnings():     # "balance needs a power of 2": said in the summary line instead
            warnings.simplefilter("ignore", UserWarning)
            points = sampler.random(count)
        return [[float(p) for p in points[:, a]] for a in range(axes)]
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


def refuse_oversized(plan: VariationPlan, options: StrategyOptions, limit: int | None,
                     sizes: Sequence[int] | None = None) -> covering_size.CoveringEstimate:
    """:class:`StrategyError` when the covering array of ``plan`` (its dimensions of ``sizes`` values;
    default: all of them, before any is checked) would be beyond ``limit`` or the builder's memory."""
    found = covering_size.estimate(plan.sizes if sizes is None else sizes, options.t)
    tracks_tuples = options.t > 2 or plan.constraints is not None
    refused = covering_size.refusal(found, limit, tracks_tuples) if limit else None
    if refused is not None:
        raise StrategyError(refused, Location(str(plan.path), 0, 0), hint=covering_size.alternatives(found, limit or 0))
    return found


def build_covering_array(plan: VariationPlan, options: StrategyOptions,
                         seeds: Sequence[tuple[int, ...]] = (), *, limit: int | None = None,
                         tick: Tick | None = None) -> TupleCoverage:
    """After the values are checked: choose rows covering every coverable t-tuple; sets ``plan.rows``.

    ``seeds`` are rows written before (``--only-new``): the tuples they cover count as covered, and
    only the rows still needed are chosen (a ``t-way --strength 3`` run after a pairwise one adds
    rows for the triples the pairwise rows miss). An array that needs more rows than ``limit``
    (``--max-variants``), or more tuples than the builder can hold, is refused before it is built
    (:mod:`coverage_engine.variation.covering_size`); ``tick(done, total)`` reports progress.
    """
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
    tables = plan.constraints
    found = refuse_oversized(plan, options, limit, [len(values) for values in allowed])
    if t == 2 and tables is None:          # the common case has fast builders of its own
        pairs = sum(len(allowed[a]) * len(allowed[b]) for a, b in itertools.combinations(range(len(sizes)), 2))
        every = sum(sizes[a] * sizes[b] for a, b in itertools.combinations(range(len(sizes)), 2))
        many = found.least_rows * len(sizes) ** 2 * max(sizes) > AETG_WORK
        plan.rows = (ipog_pairwise(sizes, allowed, rng, seeds, tick) if many
                     else pairwise_rows(sizes, allowed, rng, seeds))
        return TupleCoverage(2, pairs, pairs, every - pairs)
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
    plan.rows = _drop_redundant(rows, groups)
    return TupleCoverage(t, coverable, coverable, impossible)


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


def _bad_values(plan: VariationPlan) -> list[set[int]]:
    """Per axis, the values that never resolve (from single-dimension slots; joint slots are left to rejection)."""
    bad: list[set[int]] = [set() for _ in plan.sizes]
    for slot, options in zip(plan.slots, plan.bad_options(), strict=True):
        if len(slot.dims) == 1:
            bad[slot.dims[0]] = set(options)
    return bad

