"""Plan a variation: find the dimensions, check every value once, then stream the valid combinations.

Why not resolve every combination? 100,000 variants would mean 100,000 resolutions. Instead each
dimension is a *slot* that only its own keep fills, so a value is checked once, in its slot, with
every other slot at a value known to be good:

1. **Baseline**: resolve the text with every slot at its first value (the *reference*). If that fails
   and the error's line lies inside one of the varied constraints, that slot's reference value is
   marked bad and the next value becomes the reference; if the line says nothing, each slot in turn
   is moved to another value until the baseline resolves. If nothing helps, the file itself is wrong:
   the error is raised and nothing is generated.
2. **Values**: for each slot, each other value is resolved once, all other slots at their reference.
   A value that fails makes every combination containing it fail; it is recorded with its error.
3. **Product**: combinations are produced with :func:`itertools.product` in source order (the first
   keep varies slowest, the parameter documents fastest); those containing a bad value are reported
   as skipped, the rest are valid. Nothing is held per combination, so memory is flat.

That is ``1 + Σ (values - 1)`` resolutions instead of ``Π values``. Several keeps on the *same*
parameter (same invocation or scenario member) can contradict each other, so they share one slot
whose values are their joint product. The documents of a ``--scenario-parameter-file`` form one
more slot (its choice is the overrides passed to the resolver). See ``docs/variation.md``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from coverage_engine.errors import OscError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve.overrides import scenario_overrides
from coverage_engine.variation.conditions import (
    ConstraintTables,
    Evaluate,
    condition_evaluator,
    find_conditions,
)
from coverage_engine.variation.dimensions import Dimension, find_dimensions, scenario_names
from coverage_engine.variation.drawn import DrawnChoices
from coverage_engine.variation.template import TextTemplate

if TYPE_CHECKING:
    from coverage_engine.resolve.model import ScenarioFile

#: ``(concrete text, overrides) -> resolved model``; raises :class:`OscError` when it does not resolve.
Resolve = Callable[[str, "Mapping | None"], "ScenarioFile"]

#: Assignment key of the parameter-document dimension.
DOCUMENT_KEY = "parameter_document"


@dataclass(frozen=True)
class Slot:
    """Dimensions checked together (``dims``: indices into the plan's axes) and their joint options."""

    dims: tuple[int, ...]
    sizes: tuple[int, ...]

    @property
    def count(self) -> int:
        return math.prod(self.sizes)

    def option(self, choices: Sequence[int]) -> int:
        """The option number of the slot's dims' choices (mixed radix, first dim slowest)."""
        number = 0
        for dim, size in zip(self.dims, self.sizes, strict=True):
            number = number * size + choices[dim]
        return number

    def choices(self, option: int) -> dict[int, int]:
        """Dim index → choice index for option number ``option``."""
        out = {}
        for dim, size in zip(reversed(self.dims), reversed(self.sizes), strict=True):
            option, out[dim] = divmod(option, size)
        return out


@dataclass(frozen=True)
class Rejection:
    """A value (or joint values of one slot) that does not resolve, with the error and where it was written."""

    slot: Slot
    option: int
    error: OscError
    shown: dict[str, str]
    location: Location | None
    skipped: int = 0


@dataclass
class VariationPlan:
    """Everything needed to generate: axes (dimensions, then documents), template, checked values."""

    path: Path
    text: str
    unit: syntax.CompilationUnit
    dimensions: list[Dimension]
    documents: list[dict] | None
    template: TextTemplate
    slots: list[Slot]
    scenario: str
    resolutions: int = 0
    rejections: list[Rejection] = field(default_factory=list)
    _bad: list[set[int]] = field(default_factory=list)
    #: The combinations a strategy chose (choice index per axis), in generation order; None: the full product.
    rows: list[tuple[int, ...]] | None = None
    #: The choice per axis every value was checked against (set by :func:`check_plan`).
    reference: list[int] = field(default_factory=list)
    #: The keep conditions and what they forbid (None: the file has none).
    constraints: ConstraintTables | None = None
    #: Per condition text, how many combinations (full product or drawn rows) it left out.
    excluded_by: dict[str, int] = field(default_factory=dict)
    #: How the variants were chosen (``strategy lhs, samples 200, seed 7``), written in each ``.sce`` header.
    strategy_note: str | None = None
    #: The number of points a sampler was asked for (``--samples``), recorded with each drawn range.
    design_samples: int | None = None

    # -- axes ---------------------------------------------------------------------------------------

    @property
    def sizes(self) -> list[int]:
        """Number of choices per axis (each dimension, then the document axis if any)."""
        sizes = [len(d.choices) for d in self.dimensions]
        if self.documents is not None:
            sizes.append(len(self.documents))
        return sizes

    @property
    def keys(self) -> list[str]:
        keys = [d.key for d in self.dimensions]
        if self.documents is not None:
            keys.append(DOCUMENT_KEY)
        return keys

    def shown(self) -> list[Sequence[str]]:
        """Per axis, each choice as shown in headers (source text; document number)."""
        shown: list[Sequence[str]] = [d.choices.texts if isinstance(d.choices, DrawnChoices)
                                      else [c.text for c in d.choices] for d in self.dimensions]
        if self.documents is not None:
            shown.append([str(i) for i in range(len(self.documents))])
        return shown

    def stored(self) -> list[Sequence[object]]:
        """Per axis, each choice as stored in assignments."""
        stored: list[Sequence[object]] = [d.choices.values if isinstance(d.choices, DrawnChoices)
                                          else [c.stored for c in d.choices] for d in self.dimensions]
        if self.documents is not None:
            stored.append(list(range(len(self.documents))))
        return stored

    @property
    def excluded(self) -> int:
        """Combinations left out because they break a keep condition."""
        return sum(self.excluded_by.values())

    @property
    def total(self) -> int:
        """Number of combinations (valid and skipped)."""
        return math.prod(self.sizes) if self.rows is None else len(self.rows)

    def assignment(self, choices: Sequence[int]) -> dict[str, object]:
        return {key: values[c] for key, values, c in zip(self.keys, self.stored(), choices, strict=True)}

    def shown_assignment(self, choices: Sequence[int]) -> dict[str, str]:
        return {key: values[c] for key, values, c in zip(self.keys, self.shown(), choices, strict=True)}

    def overrides(self, choices: Sequence[int]) -> dict | None:
        """The parameter document of ``choices`` as the resolver takes it (the runner's ``_output_dir`` left
        out: the ``.sce`` keeps the whole document, and its run puts its results there)."""
        return None if self.documents is None else scenario_overrides(self.documents[choices[-1]])

    def concrete_text(self, choices: Sequence[int]) -> str:
        """The concrete ``.osc`` text of a combination (line numbers as in the source)."""
        return self.template.render(choices)

    # -- combinations -------------------------------------------------------------------------------

    def combinations(self) -> Iterator[tuple[int, tuple[int, ...], Rejection | None]]:
        """``(index, choices, rejection)`` for every combination in generation order.

        ``rejection`` is None for a valid combination, else the first bad value it contains.
        """
        checks = [(slot, self._bad[i], self._rejection_of(i)) for i, slot in enumerate(self.slots) if self._bad[i]]
        product: Iterator[tuple[int, ...]] = iter(self.rows) if self.rows is not None else \
            itertools.product(*(range(n) for n in self.sizes))
        if not checks:
            for index, choices in enumerate(product):
                yield index, choices, None
            return
        for index, choices in enumerate(product):
            rejection = None
            for slot, bad, reasons in checks:
                option = slot.option(choices)
                if option in bad:
                    rejection = reasons[option]
                    break
            yield index, choices, rejection

    def valid_count(self) -> int:
        """Number of combinations without a bad value (computed for the product, counted for chosen rows)."""
        if self.rows is not None:
            return sum(1 for _, _, rejection in self.combinations() if rejection is None)
        return math.prod(slot.count - len(bad) for slot, bad in zip(self.slots, self._bad, strict=True))

    def bad_options(self) -> list[set[int]]:
        """Per slot, the options (value combinations of its dimensions) that do not resolve."""
        return self._bad

    def _rejection_of(self, slot_index: int) -> dict[int, Rejection]:
        return {r.option: r for r in self.rejections if r.slot is self.slots[slot_index]}


def _slots(dimensions: list[Dimension], documents: list | None) -> list[Slot]:
    """Group dimensions on the same target into one slot; the documents are a slot of their own."""
    groups: dict[tuple, list[int]] = {}
    for i, dim in enumerate(dimensions):
        groups.setdefault(dim.target, []).append(i)
    slots = [Slot(tuple(ids), tuple(len(dimensions[i].choices) for i in ids)) for ids in groups.values()]
    if documents is not None:
        slots.append(Slot((len(dimensions),), (len(documents),)))
    return slots


def default_resolver(path: Path) -> Resolve:
    """Parse and resolve concrete texts of ``path`` (imports relative to its folder).

    Keep conditions are skipped here: a value is checked with the other slots at their reference,
    and whether a *combination* breaks a condition is :mod:`coverage_engine.variation.conditions`' job.
    """
    from coverage_engine.parse.parser import parse_text
    from coverage_engine.resolve.resolver import resolve

    file, base = str(path), path.parent

    def run(text: str, overrides: Mapping | None) -> ScenarioFile:
        return resolve(parse_text(text, file), base_dir=base, overrides=overrides, constraints="skip")

    return run


def plan_variation(path: str | Path, documents: list[dict] | None = None, *,
                   resolver: Resolve | None = None, text: str | None = None) -> VariationPlan:
    """Parse ``path``, find its dimensions and check each value (see the module docstring).

    ``documents`` are the documents of a scenario parameter file (None: no file). Raises
    :class:`OscError` when the file cannot be parsed or does not resolve whatever the values.
    """
    plan = build_plan(path, documents, text=text)
    check_plan(plan, resolver)
    return plan


def build_plan(path: str | Path, documents: list[dict] | None = None, *, text: str | None = None) -> VariationPlan:
    """Parse ``path`` and find its dimensions, without checking any value (``plan.total`` is known).

    :func:`check_plan` must be called before the plan's combinations are used.
    """
    from coverage_engine.parse.parser import parse_text

    path = Path(path)
    if text is None:
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise OscError(f"{path}: no such file") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise OscError(f"{path}: cannot read: {exc}") from exc
    unit = parse_text(text, str(path))
    try:
        dimensions = find_dimensions(unit, text)
    except OscError as exc:
        loc = exc.location
        if exc.source_line is None and loc is not None and loc.file == str(path):
            lines = text.splitlines()
            if 1 <= loc.line <= len(lines):
                exc.source_line = lines[loc.line - 1]
        raise
    names = scenario_names(unit)
    varied = [d.scenario for d in dimensions]
    scenario = varied[0] if varied else (names[0] if names else "")
    plan = VariationPlan(path=path, text=text, unit=unit, dimensions=dimensions,
                         documents=None if documents is None else list(documents),
                         template=TextTemplate.build(text, dimensions),
                         slots=_slots(dimensions, documents), scenario=scenario)
    plan._bad = [set() for _ in plan.slots]
    return plan


def check_plan(plan: VariationPlan, resolver: Resolve | None = None, evaluate: Evaluate | None = None, *,
               exclude: bool = True) -> None:
    """Steps 1 and 2 of the module docstring (raises :class:`OscError` if no value makes the file resolve),
    then the keep conditions: the combinations (or drawn rows) that break one are left out.

    ``exclude`` False finds what the conditions forbid without listing the combinations left (a covering
    array is built around them instead of filtering the full product, which may be astronomically large).
    """
    _check(plan, resolver or default_resolver(plan.path))
    conditions = find_conditions(plan.unit, plan.text, plan.dimensions, plan.documents is not None)
    if not conditions:
        return
    plan.constraints = ConstraintTables(
        conditions, plan.sizes, plan.reference, lambda c: (plan.concrete_text(c), plan.overrides(c)),
        evaluate or condition_evaluator(plan.path),
        frozenset(i for i, d in enumerate(plan.dimensions) if d.continuous is not None))
    plan.resolutions += plan.constraints.resolutions
    if not exclude or not any(c.forbidden or c.per_row for c in conditions):
        return
    if plan.rows is None:
        plan.rows = list(itertools.product(*(range(n) for n in plan.sizes)))
    exclude_rows(plan)


def exclude_rows(plan: VariationPlan) -> None:
    """Leave out the rows of ``plan.rows`` that break a keep condition (counted in ``plan.excluded``)."""
    if plan.constraints is None or plan.rows is None:
        return
    kept = []
    for row in plan.rows:
        broken = plan.constraints.violated(row)
        if broken is None:
            kept.append(row)
        else:
            plan.excluded_by[broken.text] = plan.excluded_by.get(broken.text, 0) + 1
    plan.rows = kept


def _check(plan: VariationPlan, resolver: Resolve) -> None:
    """Steps 1 and 2 of the module docstring: find good reference values, then check all others."""
    slots = plan.slots
    plan._bad = [set() for _ in slots]
    errors: list[dict[int, OscError]] = [{} for _ in slots]

    def attempt(options: list[int]) -> OscError | None:
        choices = [0] * len(plan.sizes)
        for slot, option in zip(slots, options, strict=True):
            for dim, choice in slot.choices(option).items():
                choices[dim] = choice
        plan.resolutions += 1
        try:
            resolver(plan.concrete_text(choices), plan.overrides(choices))
        except OscError as exc:
            return exc
        return None

    def next_good(s: int, after: int) -> int | None:
        return next((o for o in range(after + 1, slots[s].count) if o not in errors[s]), None)

    reference = [0] * len(slots)
    while (error := attempt(reference)) is not None:
        culprit = _attribute(plan, error)
        if culprit is None:
            culprit = _search(slots, reference, errors, attempt)
            if culprit is None:
                raise error
        errors[culprit][reference[culprit]] = error
        following = next_good(culprit, reference[culprit])
        if following is None:  # every value of this slot fails: every combination does
            break
        reference[culprit] = following
    else:
        plan.reference = [0] * len(plan.sizes)
        for slot, option in zip(slots, reference, strict=True):
            for dim, choice in slot.choices(option).items():
                plan.reference[dim] = choice
        for s, slot in enumerate(slots):
            for option in _options_to_check(plan, slot):
                if option != reference[s] and option not in errors[s]:
                    trial = list(reference)
                    trial[s] = option
                    if (error := attempt(trial)) is not None:
                        errors[s][option] = error
    _record(plan, errors)


def _options_to_check(plan: VariationPlan, slot: Slot) -> Sequence[int]:
    """The options of ``slot`` to resolve once each: all of them, except for a drawn continuous range.

    Values drawn from one range are literals of the same kind and unit between its ends, so the
    smallest and the largest drawn value stand for all of them (100,000 draws need 2 resolutions, not
    100,000).
    """
    if len(slot.dims) == 1 and slot.dims[0] < len(plan.dimensions):
        dim = plan.dimensions[slot.dims[0]]
        if dim.continuous is not None and dim.choices:
            values = list(dim.choices.values) if isinstance(dim.choices, DrawnChoices) else \
                [c.stored for c in dim.choices]
            return sorted({values.index(min(values)), values.index(max(values))})  # type: ignore[type-var]
    return range(slot.count)


def _attribute(plan: VariationPlan, error: OscError) -> int | None:
    """The slot whose varied constraint holds the error's line, if any."""
    loc = error.location
    if loc is None or loc.file != str(plan.path):
        return None
    for s, slot in enumerate(plan.slots):
        for dim in slot.dims:
            if dim < len(plan.dimensions):
                where = plan.dimensions[dim].location
                if where.line <= loc.line <= max(where.end_line, where.line):
                    return s
    return None


def _search(slots: list[Slot], reference: list[int], errors: list[dict[int, OscError]],
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


def _blamed_dim(plan: VariationPlan, slot: Slot, error: OscError) -> int:
    """The dimension of ``slot`` whose keep holds the error's line (else its first dimension).

    Several keeps on one parameter share a slot; the value to point at is the one in the keep the
    resolver complained about.
    """
    loc = error.location
    if loc is not None and loc.file == str(plan.path):
        for dim in slot.dims:
            if dim < len(plan.dimensions):
                where = plan.dimensions[dim].location
                if where.line <= loc.line <= max(where.end_line, where.line):
                    return dim
    return slot.dims[0]


def _record(plan: VariationPlan, errors: list[dict[int, OscError]]) -> None:
    plan._bad = [set(e) for e in errors]
    shown = plan.shown()
    for s, slot in enumerate(plan.slots):
        others = math.prod(o.count for i, o in enumerate(plan.slots) if i != s)
        for option, error in sorted(errors[s].items()):
            choices = slot.choices(option)
            keys = plan.keys
            location = None
            blamed = _blamed_dim(plan, slot, error)
            if blamed < len(plan.dimensions):
                location = plan.dimensions[blamed].choices[choices[blamed]].location
            plan.rejections.append(Rejection(
                slot=slot, option=option, error=error,
                shown={keys[d]: shown[d][c] for d, c in sorted(choices.items())},
                location=location, skipped=others))
