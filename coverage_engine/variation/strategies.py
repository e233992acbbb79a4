"""The strategies of ``scenario_variation``: their names, options, and the checks and notes shared by them.

``full`` (default) writes the plan's product. The others choose rows of it:

- ``pairwise`` / ``t-way --strength t``: a covering array in which every t-tuple of values (of any t
  dimensions) that some valid variant can hold appears in at least one row, chosen *after* the values
  are checked (so it avoids values that do not resolve): :mod:`coverage_engine.variation.covering`.
- ``random``, ``lhs`` (Latin hypercube), ``halton``, ``sobol``: ``--samples N`` points of the unit
  cube, drawn *before* the values are checked (each drawn value becomes a choice of its range, so it is
  checked like a listed one): :mod:`coverage_engine.variation.design`.

Each strategy is one stage of the variation (see :mod:`coverage_engine.variation`), a function from one
immutable plan value to the next. Everything is a function of the file, the options and the seed, so
the same inputs give the same variants byte for byte.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

from coverage_engine.errors import OscError
from coverage_engine.location import Location
from coverage_engine.variation.plan import ParsedVariation

STRATEGIES = ("full", "pairwise", "t-way", "random", "lhs", "halton", "sobol")
SAMPLERS = ("random", "lhs", "halton", "sobol")
COVERING = ("pairwise", "t-way")

#: Progress of a long computation: ``tick(done, total)``.
Tick = Callable[[int, int], None]

#: A sampler whose draws keep conditions reject draws up to this many times the samples asked for.
MAX_OVERSAMPLING = 64


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


def rows_of(plan: ParsedVariation, assignments: Iterable[str]) -> list[tuple[int, ...]]:
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
