"""What typed values allow: operators and their result types, member access, conversion, argument binding.

Type rules: ``int``/``uint`` promote to ``float``; physical values add and compare only with the same
physical type and scale by plain numbers; ``*`` and ``/`` of physical values give the declared physical
type with the resulting SI exponents (``speed * time`` is a ``length``); comparisons give ``bool``; ``and``/``or``/``not`` need
``bool``. Anything else is an :class:`~coverage_engine.errors.OscTypeError` at the operator. Operators
on constants are folded here (with the run-time evaluator's own operator table), so the model carries
:class:`~coverage_engine.resolve.model.Const` wherever a value is known before the run.

Nothing here resolves syntax: these are the rules :mod:`~coverage_engine.resolve.expressions` applies to
values it has already resolved.
"""

from __future__ import annotations

from collections.abc import Mapping

from coverage_engine.errors import ArgumentError, NameLookupError, OscTypeError, ResolveError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve import model
from coverage_engine.resolve.evaluate import apply_operator
from coverage_engine.resolve.scope import TypedExpr
from coverage_engine.resolve.types import (
    ANY,
    FLOAT,
    INT,
    STRING,
    UINT,
    CompoundType,
    ConversionError,
    EnumType,
    ListType,
    OscType,
    PhysicalType,
    convert,
    is_numeric,
)


def member_of(target: TypedExpr, member: str, location: Location) -> TypedExpr:
    """``target.member`` for a struct/actor value."""
    ttype = target.type
    if not isinstance(ttype, CompoundType):
        raise OscTypeError(f"'{ttype}' has no member '{member}'", location)
    if member in ttype.fields:
        mtype = ttype.fields[member].type
    elif member in ttype.variables:
        mtype = ttype.variables[member].type
    else:
        raise NameLookupError(f"'{ttype}' has no member '{member}'", location)
    expr = target.expr
    if isinstance(expr, model.MakeStruct):
        for name, value in expr.members:
            if name == member:
                return TypedExpr(value, mtype, False)
    if isinstance(expr, model.Const) and isinstance(expr.value, dict) and member in expr.value:
        return TypedExpr(model.Const(expr.value[member]), mtype, False)
    return TypedExpr(model.FieldOf(expr, member), mtype, False)


def fold(op: str, operands: tuple[TypedExpr, ...], rtype: OscType, location: Location) -> TypedExpr:
    """``op`` applied to ``operands``: a constant when all are known (errors at ``location``), else an Operation."""
    if all(o.is_const for o in operands):
        try:
            value = apply_operator(op, [o.value for o in operands])
        except ZeroDivisionError as exc:
            raise ResolveError("division by zero", location) from exc
        except Exception as exc:  # noqa: BLE001 - the operand types were checked; report anything left
            raise OscTypeError(f"cannot apply '{op}': {exc}", location) from exc
        if rtype is FLOAT:
            value = float(value)    # a physical result keeps its kind: 2 * 3s is 6, as the reference prints it
        return TypedExpr(model.Const(value), rtype, all(o.is_literal for o in operands))
    return TypedExpr(model.Operation(op, tuple(o.expr for o in operands), location), rtype, False)


def comparable(a: OscType, b: OscType) -> bool:
    """Whether ``==``/``!=`` may compare values of these types."""
    if a is ANY or b is ANY:
        return True
    if is_numeric(a) and is_numeric(b):
        return True
    return a is b or (a.name == b.name and a.kind == b.kind)


def ordered(a: OscType, b: OscType) -> bool:
    """Whether ``<``, ``<=``, ``>``, ``>=`` may order values of these types."""
    if is_numeric(a) and is_numeric(b):
        return True
    return isinstance(a, PhysicalType) and a is b or (a is STRING and b is STRING)


def arithmetic_type(op: str, a: OscType, b: OscType) -> OscType | None:
    """The result type of arithmetic ``op`` on these types, or None when it is not allowed."""
    if is_numeric(a) and is_numeric(b):
        if op == "/":
            return FLOAT
        if a is FLOAT or b is FLOAT:
            return FLOAT
        return INT
    if op == "+" and a is STRING and b is STRING:
        return STRING
    pa, pb = isinstance(a, PhysicalType), isinstance(b, PhysicalType)
    if pa and pb:
        if op in ("+", "-", "%") and a is b:
            return a
        if op == "/" and a is b:
            return FLOAT
        return None
    if pa and is_numeric(b) and op in ("*", "/"):
        return a
    if pb and is_numeric(a) and op == "*":
        return b
    return None


def exponents_of(op: str, a: OscType, b: OscType) -> dict[str, int] | None:
    """The SI exponents of ``a op b`` for ``*`` and ``/`` where a physical value takes part (ASAM's unit
    arithmetic: speed × time has m¹), or None for any other operator or operand.

    A plain number counts as dimensionless, so ``1 / 2s`` has s⁻¹; an exponent that cancels is dropped.
    """
    if op not in ("*", "/"):
        return None
    sides = []
    for side in (a, b):
        if isinstance(side, PhysicalType):
            sides.append(dict(side.exponents))
        elif is_numeric(side):
            sides.append({})
        else:
            return None
    left, right = sides
    sign = 1 if op == "*" else -1
    combined = dict(left)
    for base, power in right.items():
        combined[base] = combined.get(base, 0) + sign * power
    return {base: power for base, power in combined.items() if power}


def physical_result(exponents: dict[str, int], types: Mapping[str, OscType]) -> OscType | None:
    """The declared physical type with these SI exponents (``float`` when they all cancel), or None."""
    if not exponents:
        return FLOAT
    for declared in types.values():
        if isinstance(declared, PhysicalType) and dict(declared.exponents) == exponents:
            return declared
    return None


def coerce(value: TypedExpr, target: OscType, location: Location, what: str,
           lenient_string: bool = False, unit_required: bool = False) -> TypedExpr:
    """``value`` made to fit ``target`` (int→float, list elements…) or an error saying what did not fit.

    A single value where a list is expected becomes a one-element list (``sub_struct("a")`` for a
    ``list of string`` member), as the reference implementation accepts it.

    With ``lenient_string`` any value may go where a string is declared (action arguments such as
    ``log(msg)`` receive the value itself). With ``unit_required`` a plain number is refused where a
    physical value is declared (a parameter's default, a keep's value: ``t: time = 3`` is an error in the
    reference too); elsewhere (constructor arguments such as ``position_3d(1.0, 2.0, 3.0)``) it is read in
    SI base units, as the reference reads it.
    """
    src = value.type
    if target is ANY or src is ANY:
        return value
    if lenient_string and target is STRING:
        return value
    if isinstance(target, ListType) and not isinstance(src, ListType) and assignable(src, target.element):
        item = coerce(value, target.element, location, what)
        if item.is_const:
            return TypedExpr(model.Const([item.value]), target, item.is_literal)
        return TypedExpr(model.MakeList((item.expr,)), target, False)
    literal = value.value if value.is_literal and value.is_const else None
    if isinstance(target, PhysicalType) and src in (INT, UINT, FLOAT) and isinstance(literal, (int, float)):
        if unit_required:
            raise OscTypeError(f"{what}: a {target} needs a unit (write {literal} followed by a unit of {target}); "
                               "a plain number is read in SI base units only as a struct argument, e.g. "
                               "position_3d(1.0, 2.0, 3.0)", location)
        # a plain number written for a physical quantity is in SI base units, as the reference
        # implementation reads it (its PyBullet example writes ``position_3d(z: 0.5)``)
        return TypedExpr(model.Const(literal), target, True)
    if not assignable(src, target):
        raise OscTypeError(f"{what}: expected {target}, got {src}", location)
    if value.is_const and (target is FLOAT or target is UINT or isinstance(target, (PhysicalType, ListType))):
        try:
            converted = convert(value.value, target, what)
        except ConversionError as exc:
            raise OscTypeError(str(exc), location) from exc
        return TypedExpr(model.Const(converted), target, value.is_literal)
    return TypedExpr(value.expr, target if not isinstance(target, CompoundType) else src, value.is_literal)


def common_element(items: list[TypedExpr], mixed_ok: bool) -> OscType:
    """The element type of a list literal without an expected one: int promotes to float (as in any numeric
    context); elements of different kinds make a mixed list only where any value is accepted (``log``'s
    message prints whatever it gets), else the first element's type decides and the others are checked."""
    kinds = [i.type for i in items]
    if all(t in (INT, UINT, FLOAT) for t in kinds) and FLOAT in kinds:
        return FLOAT
    if mixed_ok and any(t is not kinds[0] for t in kinds):
        return ANY
    return kinds[0]


def physical_value(number: int | float, factor: float, offset: float) -> int | float:
    """A physical literal's value in SI base units, keeping the number kind it was written with: ``3s`` is
    3 and ``2min`` 120 (ints), ``2.0s`` 2.0 and ``200ms`` 0.2 (floats), so it prints as the reference prints
    it (log checks and process_log_check patterns depend on that)."""
    value = number * factor + offset
    if isinstance(number, int) and not isinstance(number, bool):
        rounded = round(value)
        if abs(value - rounded) < 1e-9 * max(1.0, abs(value)):
            return int(rounded)
    return float(value)


def assignable(src: OscType, target: OscType) -> bool:
    """Whether a value of type ``src`` may be given where ``target`` is declared."""
    if src is target:
        return True
    if target is FLOAT and src in (INT, UINT):
        return True
    if target is INT and src is UINT or target is UINT and src is INT:
        return True
    if isinstance(target, ListType) and isinstance(src, ListType):
        return src.element is ANY or assignable(src.element, target.element)
    if isinstance(target, CompoundType) and isinstance(src, CompoundType):
        return src.is_a(target)
    if isinstance(target, (EnumType, PhysicalType)) and type(src) is type(target):
        return src.name == target.name
    return False


def bind_arguments(parameters: list[str], arguments: tuple[syntax.Argument, ...], what: str,
                   location: Location) -> dict[str, syntax.Argument]:
    """Match positional and named arguments to ``parameters``; errors for too many, unknown or duplicate."""
    bound: dict[str, syntax.Argument] = {}
    seen_named = False
    for index, arg in enumerate(arguments):
        if arg.name is None:
            if seen_named:
                raise ArgumentError(f"{what}: positional argument after a named one", arg.location)
            if index >= len(parameters):
                raise ArgumentError(f"{what} takes {len(parameters)} argument(s), got more", arg.location)
            bound[parameters[index]] = arg
        else:
            seen_named = True
            if arg.name not in parameters:
                known = ", ".join(parameters) or "none"
                raise ArgumentError(f"{what} has no parameter '{arg.name}' (parameters: {known})", arg.location)
            if arg.name in bound:
                raise ArgumentError(f"{what}: argument '{arg.name}' given twice", arg.location)
            bound[arg.name] = arg
    return bound


def struct_value(ctype: CompoundType, values: dict[str, TypedExpr]) -> TypedExpr:
    """Fold member values into one ``dict`` constant when all are known, else a MakeStruct."""
    literal = all(v.is_literal for v in values.values())
    if all(v.is_const for v in values.values()):
        return TypedExpr(model.Const({k: v.value for k, v in values.items()}), ctype, literal)
    return TypedExpr(model.MakeStruct(ctype.name, tuple((k, v.expr) for k, v in values.items())), ctype, literal)


def members_of(value: TypedExpr) -> dict[str, TypedExpr]:
    """The members of a struct/actor value, each as a typed value (constant where known)."""
    ctype = value.type
    assert isinstance(ctype, CompoundType)
    types = {n: f.type for n, f in ctype.fields.items()} | {n: v.type for n, v in ctype.variables.items()}
    expr = value.expr
    if isinstance(expr, model.Const) and isinstance(expr.value, dict):
        return {k: TypedExpr(model.Const(v), types.get(k, ctype), value.is_literal) for k, v in expr.value.items()}
    if isinstance(expr, model.MakeStruct):
        return {k: TypedExpr(v, types.get(k, ctype), False) for k, v in expr.members}
    return {k: TypedExpr(model.FieldOf(expr, k), t, False) for k, t in types.items()}
