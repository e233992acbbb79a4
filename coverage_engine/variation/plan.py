"""The values a variation passes from stage to stage, and its first stage: parse the source, find its axes.

A variation is a chain of functions, each from one immutable value to the next::

    parse_variation → ParsedVariation           the source, its dimensions, the text template
    design (or design_points) → PlannedVariation   the rows a sampler or a search drew (or the product)
    check_values → CheckedVariation             each value resolved once, the keep conditions read
    choose_all / choose_covering / only_new → VariationPlan   the combinations to write
    output.generate → files                     one ``.sce`` per valid combination

Each stage's value is a subclass of the one before, so a later stage reads everything an earlier one
found, and :func:`advance` makes it from the previous value (nothing is filled in afterwards).

Checking (:mod:`coverage_engine.variation.checking`) does not resolve every combination.

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

import functools
import itertools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from coverage_engine.errors import OscError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.proposals import Proposal
from coverage_engine.resolve.overrides import scenario_overrides
from coverage_engine.variation.dimensions import Dimension, find_dimensions, scenario_names
from coverage_engine.variation.drawn import DrawnChoices
from coverage_engine.variation.template import TextTemplate

if TYPE_CHECKING:
    from coverage_engine.resolve.model import ScenarioFile
    from coverage_engine.variation.conditions import ConstraintTables

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


@dataclass(frozen=True)
class ParsedVariation:
    """Stage 1, *parsed*: the source, its varied dimensions (axes), the text template and the value slots.

    Each later stage is a subclass that adds what its step found, made by a function from the previous
    value (:func:`advance`); nothing is filled in afterwards. The axes are the dimensions, then the
    parameter-document axis when a parameter file was given.
    """

    path: Path
    text: str
    unit: syntax.CompilationUnit
    dimensions: tuple[Dimension, ...]
    documents: tuple[dict, ...] | None
    template: TextTemplate
    slots: tuple[Slot, ...]
    scenario: str

    @functools.cached_property
    def sizes(self) -> list[int]:
        """Number of choices per axis (each dimension, then the document axis if any). Do not change it."""
        sizes = [len(d.choices) for d in self.dimensions]
        if self.documents is not None:
            sizes.append(len(self.documents))
        return sizes

    @functools.cached_property
    def keys(self) -> list[str]:
        """The assignment key of each axis. Do not change it."""
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

    def with_dimensions(self, dimensions: Sequence[Dimension]) -> ParsedVariation:
        """The same source with ``dimensions`` as its axes (a sampler's drawn values as the choices of a range)."""
        dims = tuple(dimensions)
        return ParsedVariation(path=self.path, text=self.text, unit=self.unit, dimensions=dims,
                               documents=self.documents, template=TextTemplate.build(self.text, list(dims)),
                               slots=_slots(list(dims), self.documents), scenario=self.scenario)


@dataclass(frozen=True)
class PlannedVariation(ParsedVariation):
    """Stage 2, *planned*: the design a strategy chose before any value is checked.

    ``rows`` are the combinations a sampler (or an adaptive search) drew, one choice index per axis, in
    generation order; None means the full product (``full``, and a covering array until it is chosen).
    """

    rows: tuple[tuple[int, ...], ...] | None = None
    #: How the variants were chosen (``strategy lhs, samples 200, seed 7``), written in each ``.sce`` header.
    strategy_note: str | None = None
    #: The number of points a sampler was asked for (``--samples``), recorded with each drawn range.
    design_samples: int | None = None
    #: The round and source results of an adaptive search, written as each ``.sce``'s proposal line.
    proposal: Proposal | None = None

    @property
    def total(self) -> int:
        """Number of combinations (valid and skipped)."""
        return math.prod(self.sizes) if self.rows is None else len(self.rows)


@dataclass(frozen=True)
class CheckedVariation(PlannedVariation):
    """Stage 3, *checked*: every value resolved once (see the module docstring), the keep conditions found."""

    #: The choice per axis every value was checked against.
    reference: tuple[int, ...] = ()
    #: Per slot, the options (value combinations of its dimensions) that do not resolve.
    bad: tuple[frozenset[int], ...] = ()
    rejections: tuple[Rejection, ...] = ()
    #: The keep conditions and what they forbid (None: the file has none).
    constraints: ConstraintTables | None = None
    #: Resolutions spent checking values and conditions.
    resolutions: int = 0

    def bad_options(self) -> tuple[frozenset[int], ...]:
        """Per slot, the options (value combinations of its dimensions) that do not resolve."""
        return self.bad or tuple(frozenset() for _ in self.slots)


@dataclass(frozen=True)
class VariationPlan(CheckedVariation):
    """Stage 4, *chosen*: the combinations to write, in generation order; what :func:`~coverage_engine.
    variation.output.generate` writes one ``.sce`` per valid combination of."""

    #: Per condition text, how many combinations (full product or drawn rows) it left out.
    excluded_by: Mapping[str, int] = field(default_factory=dict)
    #: ``--only-new``: assignments (stored JSON text) earlier runs wrote; passed over when writing.
    held: frozenset[str] = frozenset()
    #: The index of the first variant written (``--only-new`` numbers after the earlier runs).
    first_index: int = 0
    #: ``--only-new``: the variants are added to the earlier runs' files, which none of them replaces.
    adds_to_earlier: bool = False

    @property
    def excluded(self) -> int:
        """Combinations left out because they break a keep condition."""
        return sum(self.excluded_by.values())

    def combinations(self) -> Iterator[tuple[int, tuple[int, ...], Rejection | None]]:
        """``(index, choices, rejection)`` for every combination in generation order.

        ``rejection`` is None for a valid combination, else the first bad value it contains.
        """
        bad = self.bad_options()
        checks = [(slot, bad[i], self._rejection_of(i)) for i, slot in enumerate(self.slots) if bad[i]]
        product: Iterator[tuple[int, ...]] = iter(self.rows) if self.rows is not None else \
            itertools.product(*(range(n) for n in self.sizes))
        if not checks:
            for index, choices in enumerate(product):
                yield index, choices, None
            return
        for index, choices in enumerate(product):
            rejection = None
            for slot, slot_bad, reasons in checks:
                option = slot.option(choices)
                if option in slot_bad:
                    rejection = reasons[option]
                    break
            yield index, choices, rejection

    def valid_count(self) -> int:
        """Number of combinations without a bad value (computed for the product, counted for chosen rows)."""
        if self.rows is not None:
            return sum(1 for _, _, rejection in self.combinations() if rejection is None)
        return math.prod(slot.count - len(bad) for slot, bad in zip(self.slots, self.bad_options(), strict=True))

    def _rejection_of(self, slot_index: int) -> dict[int, Rejection]:
        return {r.option: r for r in self.rejections if r.slot is self.slots[slot_index]}


Stage = TypeVar("Stage", bound=ParsedVariation)


def advance(value: ParsedVariation, stage: type[Stage], **found: Any) -> Stage:
    """The next stage's value: every field of ``value`` (its own stage and those before), plus ``found``."""
    carried = {f.name: getattr(value, f.name) for f in fields(value) if f.name not in found}
    known = {f.name for f in fields(stage)}
    return stage(**{name: v for name, v in carried.items() if name in known}, **found)


def _slots(dimensions: Sequence[Dimension], documents: Sequence | None) -> tuple[Slot, ...]:
    """Group dimensions on the same target into one slot; the documents are a slot of their own."""
    groups: dict[tuple, list[int]] = {}
    for i, dim in enumerate(dimensions):
        groups.setdefault(dim.target, []).append(i)
    slots = [Slot(tuple(ids), tuple(len(dimensions[i].choices) for i in ids)) for ids in groups.values()]
    if documents is not None:
        slots.append(Slot((len(dimensions),), (len(documents),)))
    return tuple(slots)


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


def parse_variation(path: str | Path, documents: Sequence[dict] | None = None, *,
                    text: str | None = None) -> ParsedVariation:
    """Stage 1: parse ``path`` and find its dimensions, without checking any value (``sizes`` are known)."""
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
    docs = None if documents is None else tuple(documents)
    return ParsedVariation(path=path, text=text, unit=unit, dimensions=tuple(dimensions), documents=docs,
                           template=TextTemplate.build(text, dimensions), slots=_slots(dimensions, docs),
                           scenario=scenario)
