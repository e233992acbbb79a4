"""Stage 2 of a variation: the design, the points a strategy asks for before any value is checked.

A design is a set of points of the unit cube, one coordinate per axis (the dimensions, then the
parameter-document axis). :func:`design_points` turns them into the rows of a
:class:`PlannedVariation`: a discrete axis (list, integer or stepped range, the parameter documents)
maps a coordinate ``u`` to its value ``floor(u * k)``; a continuous range maps it to
``low + u * (high - low)``, and the drawn values become the range's choices (row ``i`` takes choice
``i``), so they are checked like listed ones. The samplers (:func:`unit_columns`: ``random``, ``lhs``
and ``halton`` written here, Halton with a seeded random shift; ``sobol`` from ``scipy.stats.qmc``,
the optional ``sampling`` extra, imported only when asked for) and an adaptive search both go
through it. ``full`` and the covering arrays plan the whole product (:func:`design`).
"""

from __future__ import annotations

import random
import warnings
from array import array
from collections.abc import Sequence
from dataclasses import replace

from coverage_engine.location import Location
from coverage_engine.proposals import Proposal
from coverage_engine.variation.dimensions import Dimension
from coverage_engine.variation.drawn import DrawnChoices
from coverage_engine.variation.plan import ParsedVariation, PlannedVariation, advance
from coverage_engine.variation.strategies import SAMPLERS, StrategyError, StrategyOptions, describe_options


def design(parsed: ParsedVariation, options: StrategyOptions, factor: int = 1,
           proposal: Proposal | None = None) -> PlannedVariation:
    """The design of a non-adaptive strategy: the whole product, or ``factor`` x ``--samples`` drawn points.

    A continuous range without a sampler is refused (it has no values to list). ``factor`` > 1 draws
    more points when the keep conditions left out too many (the note keeps the samples asked for).
    """
    note = describe_options(options)
    continuous = [d for d in parsed.dimensions if d.continuous is not None]
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
        return advance(parsed, PlannedVariation, strategy_note=note, design_samples=options.samples,
                       proposal=proposal)
    if options.samples is None:
        raise StrategyError(f"--strategy {options.strategy} needs --samples N (how many variants to draw)")
    if not parsed.sizes:        # every point would be the same variant: N copies of the scenario
        raise StrategyError(f"--strategy {options.strategy} draws points over the varied parameters, and "
                            f"{parsed.path.name} varies none; nothing to draw", Location.whole_file(str(parsed.path)),
                            hint="vary a parameter (keep(it.x in [...]) or a range), or run the scenario as it is")
    columns = unit_columns(options.strategy, options.samples * factor, len(parsed.sizes), options.seed)
    return design_points(parsed, columns, note=note, samples=options.samples, proposal=proposal)


def design_points(parsed: ParsedVariation, columns: Sequence[Sequence[float]], *, note: str | None,
                  samples: int | None = None, proposal: Proposal | None = None) -> PlannedVariation:
    """The planned variation of the points whose coordinates ``columns`` gives (one sequence per axis, each
    coordinate in [0, 1]; see the module docstring). ``note`` is written in each ``.sce`` header,
    ``samples`` recorded with each drawn range (the size of the design), ``proposal`` as its proposal line."""
    sizes = parsed.sizes
    if len(columns) != len(sizes) or len({len(c) for c in columns}) > 1:
        raise ValueError(f"a design needs one column per axis ({len(sizes)}), all of one length")
    count = len(columns[0]) if columns else 0
    dimensions: list[Dimension] = list(parsed.dimensions)
    choices: list[Sequence[int]] = []
    for axis, (size, column) in enumerate(zip(sizes, columns, strict=True)):
        spec = dimensions[axis].continuous if axis < len(dimensions) else None
        if spec is not None:                # each point draws its own value: row i takes choice i
            low, span = spec.low, spec.high - spec.low
            values = array("d", [low + min(max(p, 0.0), 1.0) * span for p in column])
            dimensions[axis] = replace(dimensions[axis], choices=DrawnChoices(values, spec))
            choices.append(range(count))
        else:                               # a discrete axis: the coordinate picks one of its values
            last = size - 1
            choices.append([min(max(int(p * size), 0), last) for p in column])
    rows = tuple(zip(*choices, strict=True)) if choices else ()
    return advance(parsed.with_dimensions(dimensions), PlannedVariation, rows=rows, strategy_note=note,
                   design_samples=samples, proposal=proposal)


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
