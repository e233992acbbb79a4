"""Find the dimensions of a variation: every ``keep(… in [v1, v2, …])`` that lists the values to try.

A dimension is one such constraint in a scenario:

* ``keep(it.<param> in [...])`` in the ``with:`` block of a behaviour invocation
  (``log() with: keep(it.msg in ["foo", "bar"])``), anywhere in the scenario's ``do`` tree;
* ``keep(<param> in [...])`` among a scenario's members, and ``keep(it[.<member>] in [...])`` in the
  ``with:`` block of a scenario parameter (``param1: test_struct with: keep(it.member2 in [...])``).

A literal list (``ListExpr``) of at least one value makes a dimension, and so does a range of two
literal ends (ASAM): ``[10kph..50kph]``, ``range(1m, 5m)``, an integer range ``[1..8]`` (the integers
from 1 to 8) and a stepped range ``range(5, 60, 5)`` (5, 10, …, 60: the upper end is included when it
falls on a step). Integer and stepped ranges are lists; a real range without a step is *continuous*
(:class:`RangeSpec`, no choices yet): only the samplers of :mod:`coverage_engine.variation.strategies`
can draw its values. Any other ``in`` there (an empty list, a string or a name on the right) is an
error at its position. The finder reads the syntax tree and never resolves;
each value keeps its exact source text (cut by :class:`~coverage_engine.parse.Location` offsets), so
a concrete variant is the source text with ``in [...]`` replaced by ``== <value>``.

Dimensions are returned in source order: the first keep in the file is the first dimension, and in
the cartesian product it varies slowest.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import cast

from coverage_engine.location import Location
from coverage_engine.parse import syntax as s


@dataclass(frozen=True, slots=True)
class Choice:
    """One value of a dimension.

    ``text`` is its source text on one line (what replaces the list); ``stored`` the value recorded in
    the assignment: the Python value for a plain literal (number, string, boolean), else ``text``.
    """

    text: str
    stored: object
    location: Location


@dataclass(frozen=True, slots=True)
class RangeSpec:
    """The ends of a range dimension as numbers in its literals' unit (``unit`` "" for plain numbers)."""

    low: float
    high: float
    unit: str
    location: Location

    def text(self, number: float) -> str:
        """A drawn value as source text (``12.5kph``): the shortest form that reads back the same."""
        return f"{number!r}{self.unit}" if self.unit else repr(number)


@dataclass(frozen=True, slots=True)
class Dimension:
    """One ``keep(<left> in [...])`` to vary.

    ``key`` names it in headers and assignments (``<scenario>.<path>``); ``target`` is the same for
    dimensions constraining the same parameter (they are checked together, see
    :mod:`coverage_engine.variation.validate`). ``start``/``end`` are the offsets of the ``in``
    expression in the file text; ``left`` the source text of its left operand.
    """

    key: str
    scenario: str
    target: tuple
    left: str
    choices: Sequence[Choice]
    start: int
    end: int
    location: Location
    #: A continuous range (its values are drawn by a sampler), else None.
    continuous: RangeSpec | None = None

    def replacement(self, choice: int) -> str:
        """The source text replacing the ``in`` expression for ``choices[choice]``."""
        return f"{self.left} == {self.choices[choice].text}"


def one_line(text: str) -> str:
    """``text`` with comments removed and each line break (with its indentation) turned into a blank.

    String literals are left untouched (OSC strings never contain a raw line break).
    """
    if "\n" not in text and "#" not in text:
        return text
    out: list[str] = []
    quote = ""
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if quote:
            out.append(c)
            if c == "\\" and i + 1 < n:
                out.append(text[i + 1])
                i += 1
            elif c == quote:
                quote = ""
        elif c in "'\"":
            quote = c
            out.append(c)
        elif c == "#":
            while i < n and text[i] != "\n":
                i += 1
            continue
        elif c in "\r\n":
            while i < n and text[i] in " \t\r\n":
                i += 1
            if out and out[-1] != " ":
                out.append(" ")
            continue
        else:
            out.append(c)
        i += 1
    return "".join(out).strip()


def _cut(text: str, location: Location) -> str:
    return text[location.start_pos:location.end_pos]


def _path(expr: s.Expression) -> list[str] | None:
    """``it.a.b`` → ``["it", "a", "b"]``; ``speed`` → ``["speed"]``; None for anything else."""
    if isinstance(expr, s.Identifier):
        return [expr.name]
    if isinstance(expr, s.MemberAccess):
        inner = _path(expr.target)
        return None if inner is None else inner + [expr.member]
    return None


def _stored(item: s.Expression, text: str) -> object:
    if isinstance(item, s.Literal) and item.kind in ("int", "float", "bool", "string"):
        return item.value
    if isinstance(item, s.UnaryOp) and item.op == "-" and isinstance(item.operand, s.Literal) \
            and item.operand.kind in ("int", "float"):
        return -cast("int | float", item.operand.value)
    return text


def _keep_dimension(keep: s.KeepConstraint, text: str, scenario: str, owner: list[str],
                    owner_target: tuple | None) -> Dimension | None:
    """The dimension of ``keep`` if it is ``<left> in [list]``.

    ``owner`` is the path of what ``it`` means here (an invocation step or a parameter name) and
    ``owner_target`` the identity of an invocation (None for scenario members); a left side not
    starting with ``it`` names scenario members.
    """
    expr = keep.expression
    if not (isinstance(expr, s.BinaryOp) and expr.op == "in"):
        return None
    _check_in(expr)
    parts = _path(expr.left)
    assert parts is not None  # checked by _check_in
    path = owner + parts[1:] if parts[0] == "it" else parts
    if parts[0] == "it" and owner_target is not None:
        target: tuple = (*owner_target, tuple(parts[1:]))
    else:
        target = (scenario, "member", tuple(path))
    choices = []
    continuous = None
    if isinstance(expr.right, s.ListExpr):
        for item in expr.right.items:
            item_text = one_line(_cut(text, item.location))
            choices.append(Choice(item_text, _stored(item, item_text), item.location))
    else:
        choices, continuous = _range_choices(expr.right)
    return Dimension(key=".".join([scenario, *path]), scenario=scenario, target=target,
                     left=one_line(_cut(text, expr.left.location)), choices=tuple(choices),
                     start=expr.location.start_pos, end=expr.location.end_pos, location=keep.location,
                     continuous=continuous)


#: Most values a stepped or integer range may list (a bigger one is a mistake, or wants a sampler).
MAX_RANGE_VALUES = 100_000


def _range_ends(right: s.Expression) -> tuple[list[s.Expression], Location]:
    if isinstance(right, s.RangeExpr):
        return [right.low, right.high], right.location
    assert isinstance(right, s.Call)
    return [a.value for a in right.arguments], right.location


def _literal_number(expr: s.Expression) -> tuple[float | int, str]:
    """A range end as (number, unit text): ``5``, ``-2.5``, ``10kph``; else an error at its place."""
    from coverage_engine.errors import ResolveError

    sign = 1
    if isinstance(expr, s.UnaryOp) and expr.op in ("-", "+"):
        sign = -1 if expr.op == "-" else 1
        expr = expr.operand
    if isinstance(expr, s.Literal) and expr.kind in ("int", "float") and not isinstance(expr.value, bool):
        return sign * cast("int | float", expr.value), ""
    if isinstance(expr, s.PhysicalLiteral):
        return sign * expr.number, expr.unit
    raise ResolveError("a range end must be a number, with or without a unit (10, 2.5, 10kph)", expr.location)


def _range_choices(right: s.Expression) -> tuple[list[Choice], RangeSpec | None]:
    """The values of a range: listed for an integer or stepped range; a :class:`RangeSpec` for a real one."""
    from coverage_engine.errors import ResolveError

    ends, where = _range_ends(right)
    numbers = [_literal_number(e) for e in ends]
    units = {unit for _, unit in numbers}
    if len(units) > 1:
        raise ResolveError(f"the ends of a range must be written in one unit (got {', '.join(sorted(units))})",
                           where)
    unit = units.pop()
    low, high = numbers[0][0], numbers[1][0]
    if not low < high:
        raise ResolveError(f"a range goes from low to high (got {low}..{high})", where)
    step = numbers[2][0] if len(numbers) == 3 else None
    if step is not None and not step > 0:
        raise ResolveError(f"the step of a range must be above 0 (got {step})", ends[2].location)
    integral = all(isinstance(n, int) for n, _ in numbers)
    if step is None and not (integral and not unit):
        return [], RangeSpec(float(low), float(high), unit, where)
    step = step if step is not None else 1
    count = int((high - low) / step + 1e-9) + 1
    if count > MAX_RANGE_VALUES:
        # (whatever the strategy: a sampler takes a stepped range's values as listed, so it must lose its step)
        raise ResolveError(f"this range lists {count:,} values (more than {MAX_RANGE_VALUES:,}); use a larger step, "
                           "or write real ends without a step (0.0..10.0) and draw values from it with "
                           "--strategy lhs|random|sobol|halton --samples N", where)
    values = [low + i * step for i in range(count)]
    if integral:
        values = [int(v) for v in values]
    else:
        values = [round(v, 12) for v in values]
    # A physical value is stored as its text (as a listed '30kph' is), a plain number as the number.
    return [Choice(f"{v!r}{unit}", f"{v!r}{unit}" if unit else v, where) for v in values], None


def _check_in(expr: s.BinaryOp) -> None:
    """Refuse, at its position, an ``in`` that cannot be a dimension (the resolver would only say
    "expand it with scenario_variation", which is what is being done)."""
    from coverage_engine.errors import ResolveError, UnsupportedFeatureError

    right = expr.right
    if isinstance(right, s.Call) and isinstance(right.callee, s.Identifier) and right.callee.name == "range":
        if len(right.arguments) not in (2, 3) or any(a.name is not None for a in right.arguments):
            raise ResolveError("range() takes a low and a high end and an optional step: range(5, 60, 5)",
                               right.location)
    elif isinstance(right, s.RangeExpr):
        pass
    elif not isinstance(right, s.ListExpr):
        raise UnsupportedFeatureError("the right side of 'in' must be a list of values ('in [v1, v2, ...]')",
                                      right.location)
    if isinstance(right, s.ListExpr) and not right.items:
        raise ResolveError("empty value list: a varied parameter needs at least one value", right.location)
    if _path(expr.left) is None:
        raise UnsupportedFeatureError("the left side of 'in' must name a parameter ('it.<name>' or '<name>')",
                                      expr.left.location)


def _invocations(node: object) -> Iterator[s.Invocation]:
    """Every invocation under a behaviour, in no particular order (callers sort by position).

    Walks all fields of composites rather than only ``members``, so the finder does not depend on
    which field the parser files a child under.
    """
    if isinstance(node, s.Invocation):
        yield node
    elif isinstance(node, s.Composite):
        for name in ("members", "arguments", "with_members"):
            value = getattr(node, name)
            for child in value if isinstance(value, tuple) else (value,):
                yield from _invocations(child)


def invocation_steps(behavior: object) -> list[tuple[str, s.Invocation]]:
    """The invocations of a ``do`` tree in source order, each with the step name its keys use: its label,
    else its action name, with ``[n]`` when that action is invoked several times (``log[1]``)."""
    invocations = sorted(_invocations(behavior), key=lambda inv: inv.location.start_pos)
    names = Counter(inv.name.dotted for inv in invocations if inv.label is None)
    seen: Counter = Counter()
    steps = []
    for inv in invocations:
        step = inv.label or inv.name.dotted
        if inv.label is None:
            if names[step] > 1:
                step = f"{step}[{seen[step]}]"
            seen[inv.name.dotted] += 1
        steps.append((step, inv))
    return steps


def _keeps(members: Iterable[object]) -> Iterator[s.KeepConstraint]:
    return (m for m in members if isinstance(m, s.KeepConstraint))


def _scenario_dimensions(decl: s.TypeDecl, text: str) -> Iterator[Dimension]:
    scenario = decl.name.dotted
    for member in decl.members:
        found: list[Dimension | None] = []
        if isinstance(member, s.ParameterDecl):
            for name in member.names:
                found += [_keep_dimension(k, text, scenario, [name], None)
                          for k in _keeps(member.with_members)]
                break  # ``a, b: int with: keep(...)``: one constraint text, named after the first
        elif isinstance(member, s.KeepConstraint):
            found.append(_keep_dimension(member, text, scenario, [], None))
        elif isinstance(member, s.DoDirective):
            for step, inv in invocation_steps(member.behavior):
                found += [_keep_dimension(k, text, scenario, [step],
                                          (scenario, "invocation", inv.location.start_pos))
                          for k in _keeps(inv.with_members)]
        yield from (d for d in found if d is not None)


def find_dimensions(unit: s.CompilationUnit, text: str | None = None) -> list[Dimension]:
    """The dimensions of every scenario in ``unit``, in source order (first one varies slowest)."""
    text = unit.text if text is None else text
    found: list[Dimension] = []
    for decl in unit.declarations:
        if isinstance(decl, s.TypeDecl) and decl.kind == "scenario":
            found.extend(_scenario_dimensions(decl, text))
    found.sort(key=lambda d: d.start)
    _check_disjoint(found)
    return _unique_keys(found)


def _unique_keys(dimensions: list[Dimension]) -> list[Dimension]:
    """Second and later keeps on the same parameter get ``#2``, ``#3`` … after the key.

    They are checked together with the first (one slot), but each keep's value is its own entry in a
    ``.sce``'s assignment (a YAML mapping, a JSON object: a key may appear only once).
    """
    from dataclasses import replace

    seen: Counter = Counter()
    out = []
    for dim in dimensions:
        seen[dim.key] += 1
        out.append(dim if seen[dim.key] == 1 else replace(dim, key=f"{dim.key}#{seen[dim.key]}"))
    return out


def _check_disjoint(dimensions: list[Dimension]) -> None:
    """Nested lists (a keep inside a value of another) cannot be cut apart: refuse them clearly."""
    from coverage_engine.errors import UnsupportedFeatureError

    for before, after in zip(dimensions, dimensions[1:], strict=False):
        if after.start < before.end:
            raise UnsupportedFeatureError("a varied constraint inside another varied constraint cannot be "
                                          "expanded", after.location)


def scenario_names(unit: s.CompilationUnit) -> list[str]:
    """Names of the scenarios declared in ``unit``, in file order."""
    return [d.name.dotted for d in unit.declarations if isinstance(d, s.TypeDecl) and d.kind == "scenario"]
