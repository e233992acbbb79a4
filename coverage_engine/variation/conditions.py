"""Keep conditions as constraints on the variation space: which combinations no variant may hold.

A *condition* is a keep that is neither a value (``keep(it.x == v)``) nor a varied list
(``keep(it.x in [...])``): ``keep(it >= 2m)``, ``keep(goal_x > start_x)``,
``keep(not (weather == snow and speed > 80kph))``. The resolver checks it once the values are known
(:mod:`coverage_engine.resolve.keeps`); here it decides which combinations are written at all.

Each condition depends on the dimensions whose parameters it names (found in the syntax: ``it`` and
``it.<member>`` relative to where the keep stands, bare names as scenario members), and on the
parameter documents when it names scenario parameters. Its outcome is then a table over the values
of those dimensions only, filled by resolving each of their combinations once in "collect" mode,
every other dimension at its reference value: a condition on two dimensions of ten values costs 100
resolutions, whatever the other dimensions. A condition over more combinations than
:data:`TABLE_LIMIT` (values drawn from a continuous range) is instead resolved once per distinct
combination of its dimensions that a row holds.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from coverage_engine.errors import ResolveError
from coverage_engine.location import Location
from coverage_engine.parse import syntax as s
from coverage_engine.variation.dimensions import Dimension, _keeps, _path, invocation_steps

#: Most combinations of a condition's dimensions resolved up front; beyond, outcomes are found per row.
TABLE_LIMIT = 4096

#: ``(concrete text, overrides) -> [(location, holds) for each condition]``.
Evaluate = Callable[[str, "Mapping | None"], list[tuple[Location, bool]]]


@dataclass
class Condition:
    """One keep condition: where it is, its text, the axes it depends on, and what it forbids."""

    location: Location
    text: str
    axes: tuple[int, ...]
    #: Combinations of ``axes`` (choice per axis) for which the condition does not hold.
    forbidden: set[tuple[int, ...]] = field(default_factory=set)
    #: Combinations found to hold (only kept for conditions resolved per row).
    allowed: set[tuple[int, ...]] = field(default_factory=set)
    per_row: bool = False

    def key(self, choices: Sequence[int]) -> tuple[int, ...]:
        return tuple(choices[a] for a in self.axes)


def find_conditions(unit: s.CompilationUnit, text: str, dimensions: list[Dimension],
                    has_documents: bool) -> list[Condition]:
    """Every keep condition of the varied scenarios, with the axes it depends on (source order)."""
    varied = {d.scenario for d in dimensions}
    found: list[Condition] = []
    for decl in unit.declarations:
        if not (isinstance(decl, s.TypeDecl) and decl.kind == "scenario"):
            continue
        scenario = decl.name.dotted
        if varied and scenario not in varied:
            continue
        for keep, owner in _scenario_keeps(decl):
            if not _is_condition(keep):
                continue
            paths = [owner + p[1:] if p[0] == "it" else p for p in _names(keep.expression)]
            axes = [i for i, d in enumerate(dimensions)
                    if d.scenario == scenario and any(_related(_dim_path(d), p) for p in paths)]
            if has_documents and (not owner or owner[0] in _parameter_names(decl)):
                axes.append(len(dimensions))      # parameter documents may override what it names
            found.append(Condition(keep.location, " ".join(text[keep.location.start_pos:
                                                                  keep.location.end_pos].split()),
                                   tuple(axes)))
    return found


def _scenario_keeps(decl: s.TypeDecl) -> Iterator[tuple[s.KeepConstraint, list[str]]]:
    """Each keep of a scenario with what ``it`` means there (``[]``: the scenario itself)."""
    for member in decl.members:
        if isinstance(member, s.KeepConstraint):
            yield member, []
        elif isinstance(member, s.ParameterDecl):
            for keep in _keeps(member.with_members):
                yield keep, [member.names[0]]
        elif isinstance(member, s.DoDirective):
            for step, inv in invocation_steps(member.behavior):
                for keep in _keeps(inv.with_members):
                    yield keep, [step]


def _parameter_names(decl: s.TypeDecl) -> set[str]:
    return {name for m in decl.members if isinstance(m, s.ParameterDecl) for name in m.names}


def _is_condition(keep: s.KeepConstraint) -> bool:
    expr = keep.expression
    if keep.is_default:
        return False
    if isinstance(expr, s.UnaryOp):
        return expr.op == "not"
    return isinstance(expr, s.BinaryOp) and expr.op not in ("==", "in")


def _names(expr: object) -> Iterator[list[str]]:
    """The member paths an expression reads (``it.a.b``, ``speed``), outermost chains only."""
    path = _path(expr) if isinstance(expr, (s.Identifier, s.MemberAccess)) else None
    if path is not None:
        yield path
        return
    if isinstance(expr, s.BinaryOp):
        yield from _names(expr.left)
        yield from _names(expr.right)
    elif isinstance(expr, s.UnaryOp):
        yield from _names(expr.operand)
    elif isinstance(expr, s.Call):
        for argument in expr.arguments:
            yield from _names(argument.value)
    elif isinstance(expr, s.ListExpr):
        for item in expr.items:
            yield from _names(item)


def _dim_path(dim: Dimension) -> list[str]:
    """A dimension's parameter path below its scenario (``test.log.msg#2`` → ``["log", "msg"]``)."""
    key = dim.key.split("#", 1)[0]
    return key.split(".")[1:] if "." in key else []


def _related(a: list[str], b: list[str]) -> bool:
    """One path is the other or lies below it (``p`` and ``p.x``: a condition on ``p`` reads ``p.x``)."""
    n = min(len(a), len(b))
    return n > 0 and a[:n] == b[:n]


def condition_evaluator(path: Path) -> Evaluate:
    """Resolve concrete texts of ``path`` in "collect" mode: every condition's location and outcome."""
    from coverage_engine.parse.parser import parse_text
    from coverage_engine.resolve.resolver import resolve

    file, base = str(path), path.parent

    def run(text: str, overrides: Mapping | None) -> list[tuple[Location, bool]]:
        collected: list[tuple[Location, bool]] = []
        resolve(parse_text(text, file), base_dir=base, overrides=overrides, constraints="collect",
                collected=collected)
        return collected

    return run


class ConstraintTables:
    """The outcome of every condition for the combinations of its axes, filled on demand.

    ``concrete(choices)`` gives the text and overrides of a combination; ``reference`` the choice
    per axis used for the axes a condition does not depend on.
    """

    def __init__(self, conditions: list[Condition], sizes: Sequence[int], reference: Sequence[int],
                 concrete: Callable[[Sequence[int]], tuple[str, Mapping | None]], evaluate: Evaluate,
                 sampled: frozenset[int] = frozenset()) -> None:
        self.conditions = conditions
        #: Axes whose values are a draw from a continuous range (a sample, not every value there is).
        self.sampled = sampled
        self.sizes = list(sizes)
        self.reference = list(reference)
        self.concrete = concrete
        self.evaluate = evaluate
        self.resolutions = 0
        for condition in conditions:
            count = math.prod(self.sizes[a] for a in condition.axes)
            condition.per_row = count > TABLE_LIMIT
            if not condition.per_row:
                self._fill(condition)

    def _outcomes(self, choices: Sequence[int]) -> dict[int, bool]:
        """Line → holds, for every condition, in the combination ``choices``."""
        text, overrides = self.concrete(choices)
        self.resolutions += 1
        outcome: dict[int, bool] = {}
        for location, holds in self.evaluate(text, overrides):
            outcome[location.line] = outcome.get(location.line, True) and holds
        return outcome

    def _fill(self, condition: Condition) -> None:
        for values in itertools.product(*(range(self.sizes[a]) for a in condition.axes)):
            choices = list(self.reference)
            for axis, value in zip(condition.axes, values, strict=True):
                choices[axis] = value
            if not self._outcomes(choices).get(condition.location.line, True):
                condition.forbidden.add(values)
        if condition.axes and len(condition.forbidden) == math.prod(self.sizes[a] for a in condition.axes) \
                and not self.sampled.intersection(condition.axes):     # a larger draw may still hold
            raise ResolveError(f"no variant satisfies keep: {condition.text} (it fails for every value of "
                               "the parameters it names)", condition.location)
        if not condition.axes and condition.forbidden:
            raise ResolveError(f"constraint does not hold: {condition.text}", condition.location)

    def violated(self, choices: Sequence[int]) -> Condition | None:
        """The first condition ``choices`` breaks, or None."""
        for condition in self.conditions:
            key = condition.key(choices)
            if key in condition.forbidden:
                return condition
            if condition.per_row and key not in condition.allowed:
                trial = list(self.reference)
                for axis in condition.axes:
                    trial[axis] = choices[axis]
                if self._outcomes(trial).get(condition.location.line, True):
                    condition.allowed.add(key)
                else:
                    condition.forbidden.add(key)
                    return condition
        return None

    def tuple_allowed(self, axes: Sequence[int], values: Sequence[int]) -> bool:
        """Whether a t-tuple (``values`` on ``axes``) breaks no condition whose axes it fixes entirely."""
        row: list[int | None] = [None] * len(self.sizes)
        for axis, value in zip(axes, values, strict=True):
            row[axis] = value
        return self.partial_allowed(row)

    def partial_allowed(self, row: Sequence[int | None]) -> bool:
        """Whether a partly filled row breaks no tabled condition whose axes are all filled."""
        for condition in self.conditions:
            if condition.per_row or not condition.axes:
                continue
            if all(row[a] is not None for a in condition.axes):
                if tuple(row[a] for a in condition.axes) in condition.forbidden:
                    return False
        return True
