"""Resolve syntax expressions into typed model expressions, folding constants as it goes.

Type rules: ``int``/``uint`` promote to ``float``; physical values add and compare only with the same
physical type and scale by plain numbers; comparisons give ``bool``; ``and``/``or``/``not`` need
``bool``. Anything else is an :class:`~coverage_engine.errors.OscTypeError` at the operator.
"""

from __future__ import annotations

from coverage_engine import model, syntax
from coverage_engine.errors import (
    ArgumentError,
    NameLookupError,
    OscTypeError,
    ResolveError,
    UnsupportedFeatureError,
)
from coverage_engine.evaluate import apply_operator
from coverage_engine.scope import Scope, TypedExpr
from coverage_engine.types import (
    ANY,
    BOOL,
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


def resolve_expression(expr: syntax.Expression, scope: Scope, expected: OscType | None = None) -> TypedExpr:
    """The typed model expression for ``expr`` in ``scope``; ``expected`` helps ``!member`` and lists."""
    if isinstance(expr, syntax.Literal):
        return TypedExpr(model.Const(expr.value), _LITERAL_TYPES[expr.kind], True)
    if isinstance(expr, syntax.PhysicalLiteral):
        unit = scope.ctx.namespace.units.get(expr.unit)
        if unit is None:
            raise NameLookupError(f"unknown unit '{expr.unit}'", expr.location)
        return TypedExpr(model.Const(float(expr.number) * unit.factor + unit.offset), unit.physical, True)
    if isinstance(expr, syntax.Identifier):
        return _identifier(expr, scope, expected)
    if isinstance(expr, syntax.MemberAccess):
        return member_of(resolve_expression(expr.target, scope), expr.member, expr.location, scope)
    if isinstance(expr, syntax.Call):
        return _call(expr, scope)
    if isinstance(expr, syntax.BinaryOp):
        return _binary(expr, scope)
    if isinstance(expr, syntax.UnaryOp):
        operand = resolve_expression(expr.operand, scope, expected)
        if expr.op == "not":
            _require(operand.type is BOOL, f"'not' needs a bool, got {operand.type}", expr.location)
            return _fold("not", (operand,), BOOL, expr.location)
        _require(is_numeric(operand.type) or isinstance(operand.type, PhysicalType),
                 f"unary '-' needs a number, got {operand.type}", expr.location)
        rtype = INT if operand.type is UINT else operand.type
        return _fold("neg", (operand,), rtype, expr.location)
    if isinstance(expr, syntax.ListExpr):
        return _list(expr, scope, expected)
    if isinstance(expr, syntax.EnumValueRef):
        return _enum_value(expr, scope, expected)
    if isinstance(expr, syntax.Ternary):
        cond = resolve_expression(expr.condition, scope, BOOL)
        _require(cond.type is BOOL, f"condition must be bool, got {cond.type}", expr.condition.location)
        if not cond.is_const:
            raise UnsupportedFeatureError("not supported: a conditional expression that depends on run-time values",
                                          expr.location)
        return resolve_expression(expr.if_true if cond.value else expr.if_false, scope, expected)
    if isinstance(expr, syntax.RangeExpr):
        raise UnsupportedFeatureError("not supported: range expressions", expr.location)
    if isinstance(expr, syntax.EventRef):
        raise ResolveError("an event reference ('@…') can only follow 'wait'", expr.location)
    raise ResolveError(f"unexpected expression {type(expr).__name__}", getattr(expr, "location", None))


_LITERAL_TYPES = {"int": INT, "uint": UINT, "float": FLOAT, "bool": BOOL, "string": STRING}


def _require(condition: bool, message: str, location: syntax.Location) -> None:
    if not condition:
        raise OscTypeError(message, location)


def _identifier(expr: syntax.Identifier, scope: Scope, expected: OscType | None) -> TypedExpr:
    if expr.name == "it":
        if scope.it is None:
            raise NameLookupError("'it' can only be used inside 'keep(...)' of a typed value", expr.location)
        return scope.it
    found = scope.lookup(expr.name)
    if found is not None:
        return TypedExpr(found.expr, found.type, False)
    ctx = scope.ctx
    if expr.name in ctx.namespace.globals:
        from coverage_engine.instances import global_value

        value = global_value(ctx, expr.name, expr.location)
        return TypedExpr(value.expr, value.type, False)
    named_type = ctx.namespace.types.get(expr.name)
    if isinstance(named_type, CompoundType) and named_type.kind == "struct":
        from coverage_engine.instances import instantiate

        value = instantiate(ctx, named_type, {}, [], ctx.fresh_path(named_type.name), expr.location)
        return TypedExpr(value.expr, value.type, True)
    raise NameLookupError(f"unknown name '{expr.name}'", expr.location)


def member_of(target: TypedExpr, member: str, location: syntax.Location, scope: Scope) -> TypedExpr:
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


def _fold(op: str, operands: tuple[TypedExpr, ...], rtype: OscType, location: syntax.Location) -> TypedExpr:
    if all(o.is_const for o in operands):
        try:
            value = apply_operator(op, [o.value for o in operands])
        except ZeroDivisionError as exc:
            raise ResolveError("division by zero", location) from exc
        except Exception as exc:  # noqa: BLE001 - the operand types were checked; report anything left
            raise OscTypeError(f"cannot apply '{op}': {exc}", location) from exc
        if rtype is FLOAT or isinstance(rtype, PhysicalType):
            value = float(value)
        return TypedExpr(model.Const(value), rtype, all(o.is_literal for o in operands))
    return TypedExpr(model.Operation(op, tuple(o.expr for o in operands), location), rtype, False)


def _binary(expr: syntax.BinaryOp, scope: Scope) -> TypedExpr:
    op = expr.op
    left = resolve_expression(expr.left, scope)
    right = resolve_expression(expr.right, scope, left.type if op in ("==", "!=") else None)
    lt, rt = left.type, right.type
    if op in ("and", "or"):
        _require(lt is BOOL and rt is BOOL, f"'{op}' needs bool operands, got {lt} and {rt}", expr.location)
        return _fold(op, (left, right), BOOL, expr.location)
    if op == "=>":
        raise UnsupportedFeatureError("not supported: the implication operator '=>'", expr.location)
    if op == "in":
        _require(isinstance(rt, ListType), f"'in' needs a list on its right, got {rt}", expr.location)
        return _fold(op, (left, right), BOOL, expr.location)
    if op in ("==", "!="):
        _require(_comparable(lt, rt), f"cannot compare {lt} with {rt}", expr.location)
        return _fold(op, (left, right), BOOL, expr.location)
    if op in ("<", "<=", ">", ">="):
        _require(_ordered(lt, rt), f"cannot order {lt} and {rt} with '{op}'", expr.location)
        return _fold(op, (left, right), BOOL, expr.location)
    rtype = _arithmetic_type(op, lt, rt)
    if rtype is None:
        raise OscTypeError(f"operator '{op}' cannot combine {lt} and {rt}", expr.location)
    return _fold(op, (left, right), rtype, expr.location)


def _comparable(a: OscType, b: OscType) -> bool:
    if a is ANY or b is ANY:
        return True
    if is_numeric(a) and is_numeric(b):
        return True
    return a is b or (a.name == b.name and a.kind == b.kind)


def _ordered(a: OscType, b: OscType) -> bool:
    if is_numeric(a) and is_numeric(b):
        return True
    return isinstance(a, PhysicalType) and a is b or (a is STRING and b is STRING)


def _arithmetic_type(op: str, a: OscType, b: OscType) -> OscType | None:
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


def _list(expr: syntax.ListExpr, scope: Scope, expected: OscType | None) -> TypedExpr:
    if not expr.items:
        raise ResolveError("an empty list literal '[]' is not supported; leave the default out instead "
                           "(a list without a default starts empty)", expr.location)
    element_expected = expected.element if isinstance(expected, ListType) else None
    items = [resolve_expression(i, scope, element_expected) for i in expr.items]
    if element_expected is not None:
        element = element_expected
    elif items:
        element = items[0].type
    else:
        element = ANY
    converted = [coerce(item, element, item_expr.location, f"list element {n}")
                 for n, (item, item_expr) in enumerate(zip(items, expr.items, strict=True))]
    ltype = ListType(element)
    literal = all(i.is_literal for i in converted)
    if all(i.is_const for i in converted):
        return TypedExpr(model.Const([i.value for i in converted]), ltype, literal)
    return TypedExpr(model.MakeList(tuple(i.expr for i in converted)), ltype, False)


def _enum_value(expr: syntax.EnumValueRef, scope: Scope, expected: OscType | None) -> TypedExpr:
    if expr.enum is None:
        if not isinstance(expected, EnumType):
            raise ResolveError(f"'!{expr.member}': the enum type cannot be inferred here", expr.location)
        etype = expected
    else:
        etype = scope.ctx.namespace.types.get(expr.enum)
        if not isinstance(etype, EnumType):
            raise NameLookupError(f"unknown enum type '{expr.enum}'", expr.location)
    if expr.member not in etype.members:
        raise NameLookupError(f"enum '{etype.name}' has no member '{expr.member}'", expr.location)
    return TypedExpr(model.Const(etype.value(expr.member)), etype, True)


def coerce(value: TypedExpr, target: OscType, location: syntax.Location, what: str,
           lenient_string: bool = False) -> TypedExpr:
    """``value`` made to fit ``target`` (int→float, list elements…) or an error saying what did not fit.

    A single value where a list is expected becomes a one-element list (``sub_struct("a")`` for a
    ``list of string`` member), as the reference implementation accepts it.

    With ``lenient_string`` any value may go where a string is declared (action arguments such as
    ``log(msg)`` receive the value itself).
    """
    src = value.type
    if target is ANY or src is ANY:
        return value
    if lenient_string and target is STRING:
        return value
    if isinstance(target, ListType) and not isinstance(src, ListType) and _assignable(src, target.element):
        item = coerce(value, target.element, location, what)
        if item.is_const:
            return TypedExpr(model.Const([item.value]), target, item.is_literal)
        return TypedExpr(model.MakeList((item.expr,)), target, False)
    if isinstance(target, PhysicalType) and src in (INT, UINT, FLOAT) and value.is_literal and value.is_const:
        # a plain number written for a physical quantity is in SI base units, as the reference
        # implementation reads it (its PyBullet example writes ``position_3d(z: 0.5)``)
        return TypedExpr(model.Const(float(value.value)), target, True)
    if not _assignable(src, target):
        raise OscTypeError(f"{what}: expected {target}, got {src}", location)
    if value.is_const and (target is FLOAT or target is UINT or isinstance(target, (PhysicalType, ListType))):
        try:
            converted = convert(value.value, target, what)
        except ConversionError as exc:
            raise OscTypeError(str(exc), location) from exc
        return TypedExpr(model.Const(converted), target, value.is_literal)
    return TypedExpr(value.expr, target if not isinstance(target, CompoundType) else src, value.is_literal)


def _assignable(src: OscType, target: OscType) -> bool:
    if src is target:
        return True
    if target is FLOAT and src in (INT, UINT):
        return True
    if target is INT and src is UINT or target is UINT and src is INT:
        return True
    if isinstance(target, ListType) and isinstance(src, ListType):
        return src.element is ANY or _assignable(src.element, target.element)
    if isinstance(target, CompoundType) and isinstance(src, CompoundType):
        return src.is_a(target)
    if isinstance(target, (EnumType, PhysicalType)) and type(src) is type(target):
        return src.name == target.name
    return False


def _call(expr: syntax.Call, scope: Scope) -> TypedExpr:
    callee = expr.callee
    ctx = scope.ctx
    if isinstance(callee, syntax.Identifier):
        ctype = ctx.namespace.types.get(callee.name)
        if isinstance(ctype, CompoundType) and ctype.kind in ("struct", "actor"):
            from coverage_engine.instances import construct

            return construct(ctx, ctype, expr.arguments, scope, expr.location)
        if callee.name == "elapsed":
            raise ResolveError("'elapsed(...)' can only follow 'wait'", expr.location)
        raise NameLookupError(f"unknown function or struct '{callee.name}'", callee.location)
    if isinstance(callee, syntax.MemberAccess):
        method, owner = _method_of(callee, scope)
        from coverage_engine.methods import call_external

        return call_external(ctx, method, owner, expr.arguments, scope, expr.location)
    raise ResolveError("this expression cannot be called", expr.location)


def _method_of(callee: syntax.MemberAccess, scope: Scope) -> tuple[syntax.MethodDecl, CompoundType]:
    target = callee.target
    ctype: CompoundType | None = None
    if isinstance(target, syntax.Identifier) and scope.lookup(target.name) is None:
        named = scope.ctx.namespace.types.get(target.name)
        if isinstance(named, CompoundType):
            ctype = named
    if ctype is None:
        value = resolve_expression(target, scope)
        if not isinstance(value.type, CompoundType):
            raise OscTypeError(f"'{value.type}' has no methods", callee.location)
        ctype = value.type
    method = ctype.methods.get(callee.member)
    if method is None:
        raise NameLookupError(f"'{ctype.name}' has no method '{callee.member}'", callee.location)
    return method, ctype


def bind_arguments(parameters: list[str], arguments: tuple[syntax.Argument, ...], what: str,
                   location: syntax.Location) -> dict[str, syntax.Argument]:
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
