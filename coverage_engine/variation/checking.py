"""Stage 3 of a variation: check every value once, then find what the keep conditions forbid.

Steps 1 and 2 of :mod:`coverage_engine.variation.plan` (the baseline, then each other value with the
other slots at their reference) turn a :class:`PlannedVariation` into a :class:`CheckedVariation`:
the reference choices, the options of each slot that do not resolve (with their errors), and the
keep conditions with their tables. Which combinations are then written is the next stage's choice
(:mod:`coverage_engine.variation.choice`, :mod:`coverage_engine.variation.covering`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from coverage_engine.errors import OscError
from coverage_engine.variation.conditions import (
    ConstraintTables,
    Evaluate,
    condition_evaluator,
    find_conditions,
)
from coverage_engine.variation.drawn import DrawnChoices
from coverage_engine.variation.plan import (
    CheckedVariation,
    PlannedVariation,
    Rejection,
    Resolve,
    Slot,
    advance,
    default_resolver,
)

#: Per slot, option → the error its value gave.
_Errors = list[dict[int, OscError]]


def check_values(planned: PlannedVariation, resolver: Resolve | None = None,
                 evaluate: Evaluate | None = None) -> CheckedVariation:
    """Resolve each value once (raises :class:`OscError` if no value makes the file resolve), then read
    the keep conditions: what each forbids is known afterwards, nothing is left out yet."""
    counter = [0]
    run = resolver or default_resolver(planned.path)

    def attempt(choices: Sequence[int]) -> OscError | None:
        counter[0] += 1
        try:
            run(planned.concrete_text(choices), planned.overrides(choices))
        except OscError as exc:
            return exc
        return None

    reference, errors = _check(planned, attempt)
    checked = advance(planned, CheckedVariation, reference=reference,
                      bad=tuple(frozenset(e) for e in errors), rejections=_rejections(planned, errors),
                      resolutions=counter[0])
    conditions = find_conditions(planned.unit, planned.text, list(planned.dimensions), planned.documents is not None)
    if not conditions:
        return checked
    constraints = ConstraintTables(
        conditions, planned.sizes, reference, lambda c: (planned.concrete_text(c), planned.overrides(c)),
        evaluate or condition_evaluator(planned.path),
        frozenset(i for i, d in enumerate(planned.dimensions) if d.continuous is not None))
    return advance(checked, CheckedVariation, constraints=constraints,
                   resolutions=checked.resolutions + constraints.resolutions)


def _check(planned: PlannedVariation,
           resolves: Callable[[Sequence[int]], OscError | None]) -> tuple[tuple[int, ...], _Errors]:
    """Steps 1 and 2: find good reference values, then check all others; the reference choice per axis
    and, per slot, the options that failed with their errors."""
    slots = planned.slots
    errors: _Errors = [{} for _ in slots]

    def attempt(options: Sequence[int]) -> OscError | None:
        choices = [0] * len(planned.sizes)
        for slot, option in zip(slots, options, strict=True):
            for dim, choice in slot.choices(option).items():
                choices[dim] = choice
        return resolves(choices)

    def next_good(s: int, after: int) -> int | None:
        return next((o for o in range(after + 1, slots[s].count) if o not in errors[s]), None)

    reference = [0] * len(slots)
    while (error := attempt(reference)) is not None:
        culprit = _attribute(planned, error)
        if culprit is None:
            culprit = _search(slots, reference, errors, attempt)
            if culprit is None:
                raise error
        errors[culprit][reference[culprit]] = error
        following = next_good(culprit, reference[culprit])
        if following is None:  # every value of this slot fails: every combination does
            return (), errors
        reference[culprit] = following
    for s, slot in enumerate(slots):
        for option in _options_to_check(planned, slot):
            if option != reference[s] and option not in errors[s]:
                trial = list(reference)
                trial[s] = option
                if (error := attempt(trial)) is not None:
                    errors[s][option] = error
    choices = [0] * len(planned.sizes)
    for slot, option in zip(slots, reference, strict=True):
        for dim, choice in slot.choices(option).items():
            choices[dim] = choice
    return tuple(choices), errors


def _options_to_check(planned: PlannedVariation, slot: Slot) -> Sequence[int]:
    """The options of ``slot`` to resolve once each: all of them, except for a drawn continuous range.

    Values drawn from one range are literals of the same kind and unit between its ends, so the
    smallest and the largest drawn value stand for all of them (100,000 draws need 2 resolutions, not
    100,000).
    """
    if len(slot.dims) == 1 and slot.dims[0] < len(planned.dimensions):
        dim = planned.dimensions[slot.dims[0]]
        if dim.continuous is not None and dim.choices:
            values = list(dim.choices.values) if isinstance(dim.choices, DrawnChoices) else \
                [c.stored for c in dim.choices]
            return sorted({values.index(min(values)), values.index(max(values))})  # type: ignore[type-var]
    return range(slot.count)


def _keep_holding(planned: PlannedVariation, dims: Sequence[int], error: OscError) -> int | None:
    """The first of ``dims`` whose varied keep holds the error's line, if any."""
    loc = error.location
    if loc is None or loc.file != str(planned.path):
        return None
    for dim in dims:
        if dim < len(planned.dimensions):
            where = planned.dimensions[dim].location
            if where.line <= loc.line <= max(where.end_line, where.line):
                return dim
    return None


def _attribute(planned: PlannedVariation, error: OscError) -> int | None:
    """The slot whose varied constraint holds the error's line, if any."""
    return next((s for s, slot in enumerate(planned.slots)
                 if _keep_holding(planned, slot.dims, error) is not None), None)


def _search(slots: Sequence[Slot], reference: list[int], errors: _Errors,
            attempt: Callable[[list[int]], OscError | None]) -> int | None:
    """Move one slot at a time to another value; the slot whose move makes it resolve is the culprit."""
    for s, slot in enumerate(slots):
        for option in range(slot.count):
            if option == reference[s] or option in errors[s]:
                continue
            trial = list(reference)
            trial[s] = option
            if attempt(trial) is None:
                return s
    return None


def _rejections(planned: PlannedVariation, errors: _Errors) -> tuple[Rejection, ...]:
    """One :class:`Rejection` per failing option, pointing at the value in the keep the resolver blamed.

    Several keeps on one parameter share a slot; the value pointed at is the one in the keep the
    resolver complained about (else the slot's first dimension).
    """
    shown, keys = planned.shown(), planned.keys
    found = []
    for s, slot in enumerate(planned.slots):
        others = math.prod(o.count for i, o in enumerate(planned.slots) if i != s)
        for option, error in sorted(errors[s].items()):
            choices = slot.choices(option)
            blamed = _keep_holding(planned, slot.dims, error)
            blamed = slot.dims[0] if blamed is None else blamed
            location = planned.dimensions[blamed].choices[choices[blamed]].location \
                if blamed < len(planned.dimensions) else None
            found.append(Rejection(slot=slot, option=option, error=error,
                                   shown={keys[d]: shown[d][c] for d, c in sorted(choices.items())},
                                   location=location, skipped=others))
    return tuple(found)
