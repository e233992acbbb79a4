"""Resolve a scenario's ``cover()`` and ``record()`` members into :class:`~coverage_engine.resolve.model.CoverageItem`.

The forms (ASAM OpenSCENARIO DSL 2, coverage; the spellings Foretify users write):

- ``cover(speed)`` / ``cover(name: speed)``: a cover item named after a parameter or variable of the
  scenario, whose value it samples;
- ``cover(ttc, expression: a - b, unit: s, range: [0..10], every: 2, event: finish, text: "…",
  ignore: a > 5)``: any scalar expression, bucketed in equal widths of ``every`` between the ends of
  ``range`` (in ``unit``);
- ``cover(both, items: [speed, side])``: a cross of cover items of the same scenario;
- ``record(name, expression: e, unit: u, event: ev, text: "…")``: the raw value (min / median / max);
- in a parameter's ``with:`` block, ``name`` may be left out: it is the parameter's.

Every mistake is a located :class:`~coverage_engine.errors.ResolveError`: an unknown argument, an item in
``items`` the scenario does not declare, ``every`` without ``range``, a unit that is not one of the
expression's physical type, a value that is not a scalar, a name declared twice.
"""

from __future__ import annotations

from coverage_engine.errors import NameLookupError, OscTypeError, ResolveError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve import model
from coverage_engine.resolve.expressions import resolve_expression
from coverage_engine.resolve.operations import coerce
from coverage_engine.resolve.scope import Scope, TypedExpr
from coverage_engine.resolve.types import BOOL, FLOAT, INT, STRING, UINT, CompoundType, EnumType, PhysicalType

#: Named arguments each kind accepts.
_COVER_ARGUMENTS = ("name", "expression", "unit", "range", "every", "event", "text", "ignore", "items")
_RECORD_ARGUMENTS = ("name", "expression", "unit", "event", "text")
#: Events every scenario has besides its declared ones.
BUILTIN_EVENTS = ("end", "finish")


def resolve_coverage(stype: CompoundType, scope: Scope) -> tuple[model.CoverageItem, ...]:
    """The coverage items of scenario ``stype``, in declaration order, crosses checked against the rest."""
    items: list[model.CoverageItem] = []
    seen: dict[str, Location] = {}
    for decl, parameter in stype.coverage:
        item = _item(decl, parameter, scope)
        if item.name in seen:
            raise ResolveError(f"coverage item '{item.name}' is declared twice (first at line {seen[item.name].line})",
                               decl.location)
        seen[item.name] = decl.location
        items.append(item)
    covers = {i.name: i for i in items if i.kind == "cover" and not i.items}
    for item in items:
        for name in item.items:
            if name not in covers:
                known = ", ".join(covers) or "none"
                raise NameLookupError(f"cross '{item.name}': no cover item '{name}' in scenario '{stype.name}' "
                                      f"(cover items: {known})", item.location)
    return tuple(items)


def _item(decl: syntax.CoverageDecl, parameter: str | None, scope: Scope) -> model.CoverageItem:
    allowed = _COVER_ARGUMENTS if decl.kind == "cover" else _RECORD_ARGUMENTS
    named: dict[str, syntax.Argument] = {}
    positional: list[syntax.Argument] = []
    for argument in decl.arguments:
        if argument.name is None:
            if named:
                raise ResolveError(f"{decl.kind}(): a positional argument after named ones", argument.location)
            positional.append(argument)
            continue
        if argument.name not in allowed:
            raise ResolveError(f"{decl.kind}() has no argument '{argument.name}' (it takes: {', '.join(allowed)})",
                               argument.location)
        if argument.name in named:
            raise ResolveError(f"{decl.kind}(): argument '{argument.name}' given twice", argument.location)
        named[argument.name] = argument
    if len(positional) > 1:
        raise ResolveError(f"{decl.kind}() takes one positional argument, its name (then named ones: "
                           f"expression: …, unit: …)", positional[1].location)
    if positional:
        if "name" in named:
            raise ResolveError(f"{decl.kind}(): the name is given twice", named["name"].location)
        named["name"] = positional[0]
    name = _name(decl, named.get("name"), parameter)
    text = _string(named["text"], scope) if "text" in named else None
    event = _event(named["event"], scope) if "event" in named else "end"
    if "items" in named:
        if "expression" in named or "unit" in named or "range" in named or "every" in named:
            raise ResolveError("a cross (items: […]) has no expression, unit, range or every of its own",
                               named["items"].location)
        return model.CoverageItem("cover", name, None, "", (), None, 1.0, 0.0, None, None, event, text, None, None,
                                  _items(named["items"]), decl.location)
    source = named["expression"].value if "expression" in named else syntax.Identifier(name, decl.location)
    value = resolve_expression(source, scope)
    kind, members = _value_kind(value, decl.kind, name, source)
    unit_name, factor, offset = _unit(named.get("unit"), value, scope)
    bounds = every = None
    if "range" in named:
        if kind not in ("int", "float"):
            raise OscTypeError(f"cover '{name}': range: needs a numeric value, not {value.type}",
                               named["range"].location)
        bounds = _range(named["range"], scope, value, factor, offset)
    if "every" in named:
        if bounds is None:
            raise ResolveError(f"cover '{name}': every: needs a range: (the buckets lie between its ends)",
                               named["every"].location)
        every = _every(named["every"], scope, value, factor, bounds)
    ignore = ignore_text = None
    if "ignore" in named:
        condition = resolve_expression(named["ignore"].value, scope)
        if condition.type is not BOOL:
            raise OscTypeError(f"cover '{name}': ignore: needs a bool condition, got {condition.type}",
                               named["ignore"].location)
        ignore = condition.expr
        ignore_text = _source(named["ignore"].value.location, scope)
    return model.CoverageItem(decl.kind, name, value.expr, kind, members, unit_name, factor, offset, bounds, every,
                              event, text, ignore, ignore_text, (), decl.location)


def _name(decl: syntax.CoverageDecl, argument: syntax.Argument | None, parameter: str | None) -> str:
    if argument is None:
        if parameter is None:
            raise ResolveError(f"{decl.kind}() needs a name: {decl.kind}(speed) or {decl.kind}(name: speed, …)",
                               decl.location)
        return parameter
    if not isinstance(argument.value, syntax.Identifier):
        raise ResolveError(f"{decl.kind}(): the name must be a plain name (speed), not an expression",
                           argument.value.location)
    return argument.value.name


def _string(argument: syntax.Argument, scope: Scope) -> str:
    value = resolve_expression(argument.value, scope)
    if value.type is not STRING or not value.is_const:
        raise OscTypeError(f"text: needs a string literal, got {value.type}", argument.location)
    return str(value.expr.value)  # type: ignore[union-attr]


def _event(argument: syntax.Argument, scope: Scope) -> str:
    expr = argument.value
    if isinstance(expr, syntax.EventRef):
        name = ".".join(expr.path)
    elif isinstance(expr, syntax.Identifier):
        name = expr.name
    else:
        raise ResolveError("event: names an event (end, finish or one the scenario declares)", argument.location)
    if name not in BUILTIN_EVENTS and name not in scope.events:
        known = ", ".join([*BUILTIN_EVENTS, *scope.events])
        raise NameLookupError(f"unknown event '{name}' (events: {known})", argument.location)
    return scope.events.get(name, name)


def _items(argument: syntax.Argument) -> tuple[str, ...]:
    expr = argument.value
    if not isinstance(expr, syntax.ListExpr) or len(expr.items) < 2 \
            or not all(isinstance(i, syntax.Identifier) for i in expr.items):
        raise ResolveError("items: lists two or more cover items by name: items: [speed, side]", argument.location)
    return tuple(i.name for i in expr.items)  # type: ignore[union-attr]


def _value_kind(value: TypedExpr, kind: str, name: str, source: syntax.Expression) -> tuple[str, tuple[str, ...]]:
    vtype = value.type
    if vtype is INT or vtype is UINT:
        return "int", ()
    if vtype is FLOAT or isinstance(vtype, PhysicalType):
        return "float", ()
    if vtype is BOOL:
        return "bool", ()
    if vtype is STRING:
        return "string", ()
    if isinstance(vtype, EnumType):
        return "enum", tuple(vtype.members)
    raise OscTypeError(f"{kind} '{name}': the value must be a scalar (number, physical, bool, string or enum), "
                       f"not {vtype}", source.location)


def _unit(argument: syntax.Argument | None, value: TypedExpr, scope: Scope) -> tuple[str | None, float, float]:
    if argument is None:
        return None, 1.0, 0.0
    expr = argument.value
    if not isinstance(expr, syntax.Identifier):
        raise ResolveError("unit: names a unit (kph, s, m)", argument.location)
    unit = scope.ctx.namespace.units.get(expr.name)
    if unit is None:
        raise NameLookupError(f"unknown unit '{expr.name}'", expr.location)
    if not isinstance(value.type, PhysicalType):
        raise OscTypeError(f"unit: '{expr.name}' is a unit of {unit.physical.name}, but the value is a {value.type}, "
                           "not a physical quantity", argument.location)
    if unit.physical.exponents != value.type.exponents:
        raise OscTypeError(f"unit: '{expr.name}' is a unit of {unit.physical.name}, not of {value.type.name}",
                           argument.location)
    return unit.name, unit.factor, unit.offset


def _number(expr: syntax.Expression, scope: Scope, value: TypedExpr, factor: float, offset: float,
            what: str) -> float:
    """A range end or width as a number in the item's unit: a physical literal is converted, a plain
    number is taken as already in that unit."""
    typed = resolve_expression(expr, scope)
    if not typed.is_const:
        raise ResolveError(f"{what}: needs a constant", expr.location)
    if isinstance(typed.type, PhysicalType):
        if not isinstance(value.type, PhysicalType) or typed.type.exponents != value.type.exponents:
            raise OscTypeError(f"{what}: a {typed.type.name} does not fit a value of type {value.type}", expr.location)
        return (float(typed.expr.value) - offset) / factor  # type: ignore[union-attr, arg-type]
    number = coerce(typed, FLOAT, expr.location, what)
    return float(number.expr.value)  # type: ignore[union-attr, arg-type]


def _range(argument: syntax.Argument, scope: Scope, value: TypedExpr, factor: float,
           offset: float) -> tuple[float, float]:
    expr = argument.value
    if not isinstance(expr, syntax.RangeExpr):
        raise ResolveError("range: is written [low..high]", argument.location)
    low = _number(expr.low, scope, value, factor, offset, "range")
    high = _number(expr.high, scope, value, factor, offset, "range")
    if not low < high:
        raise ResolveError(f"range: the low end must be below the high end (got [{low:g}..{high:g}])", expr.location)
    return low, high


def _every(argument: syntax.Argument, scope: Scope, value: TypedExpr, factor: float,
           bounds: tuple[float, float]) -> float:
    width = _number(argument.value, scope, value, factor, 0.0, "every")
    if not width > 0:
        raise ResolveError(f"every: must be above 0 (got {width:g})", argument.location)
    if width > bounds[1] - bounds[0]:
        raise ResolveError(f"every: {width:g} is wider than the range ({bounds[0]:g}..{bounds[1]:g})",
                           argument.location)
    return width


def _source(location: Location, scope: Scope) -> str | None:
    """The text of an expression as written, for reports (None when the file's text is not at hand)."""
    text = scope.ctx.texts.get(location.file)
    if text is None:
        return None
    return " ".join(text[location.start_pos:location.end_pos].split()) or None
