"""Stage 4 of a variation: choose the combinations to write from a checked plan.

Each function here takes an immutable value and returns a new :class:`VariationPlan`; a strategy,
the ``--only-new`` filter or an adaptive search is one more such function between *checked* and
*written*:

* :func:`choose_all`: every combination of the design (the full product, or the rows a sampler or
  a search drew), less those that break a keep condition;
* :func:`first_samples`: a sampler's first ``--samples`` rows left after the conditions (or None:
  draw more);
* :func:`only_new`: pass over the variants earlier runs wrote and number the new ones after them.

:func:`plan_variation` chains the stages of ``--strategy full`` (parse, plan the product, check, choose all).

A covering array is chosen by :func:`coverage_engine.variation.covering.choose_covering`.
"""

from __future__ import annotations

import itertools
from collections.abc import Collection
from pathlib import Path

from coverage_engine.variation.checking import check_values
from coverage_engine.variation.plan import (
    CheckedVariation,
    PlannedVariation,
    Resolve,
    VariationPlan,
    advance,
    parse_variation,
)
from coverage_engine.variation.strategies import MAX_OVERSAMPLING, SAMPLERS, StrategyError, StrategyOptions


def choose_all(checked: CheckedVariation) -> VariationPlan:
    """Every combination of ``checked``'s design, less those that break a keep condition (counted per condition).

    Without conditions that forbid anything the full product stays implicit (None rows: it is streamed,
    never listed); otherwise it is listed once to be filtered.
    """
    constraints = checked.constraints
    if constraints is None or not any(c.forbidden or c.per_row for c in constraints.conditions):
        return advance(checked, VariationPlan)
    rows = checked.rows if checked.rows is not None else itertools.product(*(range(n) for n in checked.sizes))
    kept = []
    excluded_by: dict[str, int] = {}
    for row in rows:
        broken = constraints.violated(row)
        if broken is None:
            kept.append(row)
        else:
            excluded_by[broken.text] = excluded_by.get(broken.text, 0) + 1
    return advance(checked, VariationPlan, rows=tuple(kept), excluded_by=excluded_by)


def first_samples(plan: VariationPlan, options: StrategyOptions, factor: int) -> VariationPlan | None:
    """After the keep conditions left out some draws: the plan of the first ``samples`` rows, or None to draw more.

    The plan is final when it is not a sampler's, nothing was left out, or enough rows are kept (the
    first ``samples`` in draw order). When even :data:`MAX_OVERSAMPLING` times the samples do not give
    enough, the condition that left out the most draws is named in a :class:`StrategyError`.
    """
    if options.strategy not in SAMPLERS or options.samples is None or plan.rows is None:
        return plan
    if len(plan.rows) >= options.samples:
        return advance(plan, VariationPlan, rows=plan.rows[:options.samples])
    if factor < MAX_OVERSAMPLING:
        return None
    worst = max(plan.excluded_by.items(), key=lambda item: item[1])
    where = next((c.location for c in plan.constraints.conditions if c.text == worst[0]), None) \
        if plan.constraints is not None else None
    raise StrategyError(
        f"only {len(plan.rows)} of {options.samples * factor} drawn variants satisfy the keep conditions "
        f"({worst[0]} left out {worst[1]}); --samples {options.samples} cannot be reached", where,
        hint="widen the ranges, loosen the condition, or ask for fewer --samples")


def only_new(plan: VariationPlan, held: Collection[str], first_index: int) -> VariationPlan:
    """``--only-new``: the variants whose assignment (stored JSON text) is in ``held`` are passed over when
    written, and the others are numbered from ``first_index`` on without gaps."""
    return advance(plan, VariationPlan, held=frozenset(held), first_index=first_index, adds_to_earlier=True)


def plan_variation(path: str | Path, documents: list[dict] | None = None, *,
                   resolver: Resolve | None = None, text: str | None = None) -> VariationPlan:
    """The full product of ``path``'s dimensions, every value checked: the stages of ``--strategy full``.

    ``documents`` are the documents of a scenario parameter file (None: no file). Raises
    :class:`OscError` when the file cannot be parsed or does not resolve whatever the values.
    """
    parsed = parse_variation(path, documents, text=text)
    return choose_all(check_values(advance(parsed, PlannedVariation), resolver))
