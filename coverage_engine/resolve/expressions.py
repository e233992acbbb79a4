"""Resolve expressions: syntax expressions become typed model expressions, folded to constants where possible.

The type rules (which operands an operator takes, what it gives) are in
:mod:`~coverage_engine.resolve.operations`; this module walks the syntax and applies them. An expression
may name a global, build a struct (``pose(x: 1m)`` or a bare struct name) or call an external method:
those are resolved by :mod:`~coverage_engine.resolve.instances` and
:mod:`~coverage_engine.resolve.external_methods`, which in turn resolve their member defaults and
arguments through :attr:`ResolveContext.resolve_expression <coverage_engine.resolve.scope.ResolveContext>`
(this module's :func:`resolve_expression`, handed in by the resolver, so no module imports back up).
"""

from __future__ import annotations

from coverage_engine.errors import NameLookupError, OscTypeError, ResolveError, UnsupportedFeatureError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve import model
from coverage_engine.resolve.external_methods import call_external
from coverage_engine.resolve.instances import construct, global_value, instantiate
from coverage_engine.resolve.operations import (
    arithmetic_type,
    coerce,
    common_element,
    comparable,
    exponents_of,
    fold,
    member_of,
    ordered,
    physical_result,
    physical_value,
)
from coverage_engine.resolve.scope import Scope, TypedExpr
from coverage_engine.resolve.types import (
    ANY,
    BOOL,
    FLOAT,
    INT,
    STRING,
    UINT,
    CompoundType,
    EnumType,
    ListType,
    OscType,
    PhysicalType,
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
        return TypedExpr(model.Const(physical_value(expr.number, unit.factor, unit.offset)), unit.physical, True)
    if isinstance(expr, syntax.Identifier):
        return _identifier(expr, scope, expected)
    if isinstance(expr, syntax.MemberAccess):
        return member_of(resolve_expression(expr.target, scope), expr.member, expr.location)
    if isinstance(expr, syntax.Call):
        return _call(expr, scope)
    if isinstance(expr, syntax.BinaryOp):
        return _binary(expr, scope)
    if isinstance(expr, syntax.UnaryOp):
        operand = resolve_expression(expr.operand, scope, expected)
        if expr.op == "not":
            _require(operand.type is BOOL, f"'not' needs a bool, got {operand.type}", expr.location)
            return fold("not", (operand,), BOOL, expr.location)
        _require(is_numeric(operand.type) or isinstance(operand.type, PhysicalType),
                 f"unary '-' needs a number, got {operand.type}", expr.location)
        rtype = INT if operand.type is UINT else operand.type
        return fold("neg", (operand,), rtype, expr.location)
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


def _require(condition: bool, message: str, location: Location) -> None:
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
        value = global_value(ctx, expr.name, expr.location)
        return TypedExpr(value.expr, value.type, False)
    named_type = ctx.namespace.types.get(expr.name)
    if isinstance(named_type, CompoundType) and named_type.kind == "struct":
        value = instantiate(ctx, named_type, {}, [], ctx.fresh_path(named_type.name), expr.location)
        return TypedExpr(value.expr, value.type, True)
    raise NameLookupError(f"unknown name '{expr.name}'", expr.location)


def _binary(expr: syntax.BinaryOp, scope: Scope) -> TypedExpr:
    op = expr.op
    left = resolve_expression(expr.left, scope)
    right = resolve_expression(expr.right, scope, left.type if op in ("==", "!=") else None)
    lt, rt = left.type, right.type
    if op in ("and", "or"):
        _require(lt is BOOL and rt is BOOL, f"'{op}' needs bool operands, got {lt} and {rt}", expr.location)
        return fold(op, (left, right), BOOL, expr.location)
    if op == "=>":
        raise UnsupportedFeatureError("not supported: the implication operator '=>'", expr.location)
    if op == "in":
        _require(isinstance(rt, ListType), f"'in' needs a list on its right, got {rt}", expr.location)
        return fold(op, (left, right), BOOL, expr.location)
    if op in ("==", "!="):
        # a variable an action fills (result_variable: result) holds whatever the action stored there, as in
        # the reference, so it compares with any value
        filled = isinstance(left.expr, model.VariableRef) or isinstance(right.expr, model.VariableRef)
        _require(filled or comparable(lt, rt), f"cannot compare {lt} with {rt}", expr.location)
        return fold(op, (left, right), BOOL, expr.location)
    if op in ("<", "<=", ">", ">="):
        _require(ordered(lt, rt), f"cannot order {lt} and {rt} with '{op}'", expr.location)
        return fold(op, (left, right), BOOL, expr.location)
    rtype = arithmetic_type(op, lt, rt)
    if rtype is None:
        exponents = exponents_of(op, lt, rt)
        if exponents is None:
            raise OscTypeError(f"operator '{op}' cannot combine {lt} and {rt}", expr.location)
        rtype = physical_result(exponents, scope.ctx.namespace.types)
        if rtype is None:
            si = ", ".join(f"{base}: {power}" for base, power in exponents.items())
            raise OscTypeError(f"operator '{op}' of {lt} and {rt} gives SI({si}), and no physical type with these "
                               "exponents is declared (declare one: 'type NAME is SI(...)')", expr.location)
    return fold(op, (left, right), rtype, expr.location)


def _list(expr: syntax.ListExpr, scope: Scope, expected: OscType | None) -> TypedExpr:
    if not expr.items:
        raise ResolveError("an empty list literal '[]' is not supported; leave the default out instead "
                           "(a list without a default starts empty)", expr.location)
    element_expected = expected.element if isinstance(expected, ListType) else None
    items = [resolve_expression(i, scope, element_expected) for i in expr.items]
    if element_expected is not None:
        element = element_expected
    else:
        element = common_element(items, mixed_ok=expected is STRING or expected is ANY)
    # An int among floats is a float by type, but keeps its value as written (printed ``[-3, -0.5]``).
    converted = [TypedExpr(item.expr, FLOAT, item.is_literal) if element is FLOAT and item.type in (INT, UINT)
                 else coerce(item, element, item_expr.location, f"list element {n}")
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
        named = scope.ctx.namespace.types.get(expr.enum)
        if not isinstance(named, EnumType):
            raise NameLookupError(f"unknown enum type '{expr.enum}'", expr.location)
        etype = named
    if expr.member not in etype.members:
        raise NameLookupError(f"enum '{etype.name}' has no member '{expr.member}'", expr.location)
    return TypedExpr(model.Const(etype.value(expr.member)), etype, True)


def _call(expr: syntax.Call, scope: Scope) -> TypedExpr:
    callee = expr.callee
    ctx = scope.ctx
    if isinstance(callee, syntax.Identifier):
        ctype = ctx.namespace.types.get(callee.name)
        if isinstance(ctype, CompoundType) and ctype.kind in ("struct", "actor"):
            return construct(ctx, ctype, expr.arguments, scope, expr.location)
        if callee.name == "elapsed":
            raise ResolveError("'elapsed(...)' can only follow 'wait'", expr.location)
        if callee.name == "range":
            raise UnsupportedFeatureError("range(...) is a set of values: it stands on the right of "
                                          "'keep(x in range(...))', which scenario_variation expands", expr.location)
        raise NameLookupError(f"unknown function or struct '{callee.name}'", callee.location)
    if isinstance(callee, syntax.MemberAccess):
        method, owner = _method_of(callee, scope)
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

