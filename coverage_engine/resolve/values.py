"""Resolve values: expressions, struct/actor/scenario instances and external method calls, in one module.

These three recurse into each other the way the language does -- an expression may name a global or
construct a struct, an instance's members have default expressions, a method's arguments are
expressions -- so they live together instead of in three modules with back edges.

**Expressions** become typed model expressions, folded to constants where possible (the type rules
are in :mod:`~coverage_engine.resolve.operations`).

**Instances**: a member's value comes from, in order: an argument given to the constructor (or a
parameter override), a ``keep(it.member == v)`` on the instance, a ``keep`` written in the type, the
member's default, and finally the zero value of its type (a default-built instance for struct types).
``var`` members become :class:`~coverage_engine.resolve.model.Variable` s keyed by their path.

**External methods** (``def f(a: int = 1) -> string is external module.function()``): a call is
checked here (arguments against the signature, defaults with their declared types) and becomes a
:class:`~coverage_engine.resolve.model.ExternalCall`; the Python function is imported only when the
call is computed at run time.
"""

from __future__ import annotations

from collections.abc import Callable

from coverage_engine.errors import (
    ArgumentError,
    NameLookupError,
    OscTypeError,
    ResolveError,
    UnsupportedFeatureError,
)
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve import model
from coverage_engine.resolve.keeps import check_keep, split_type_keeps, split_with_keeps
from coverage_engine.resolve.operations import (
    arithmetic_type,
    bind_arguments,
    coerce,
    common_element,
    comparable,
    exponents_of,
    fold,
    member_of,
    members_of,
    ordered,
    physical_result,
    physical_value,
    struct_value,
)
from coverage_engine.resolve.scope import KeepValue, ResolveContext, Scope, TypedExpr
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
    zero_value,
)

# --------------------------------------------------------------------------------------------------
# Expressions


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


# --------------------------------------------------------------------------------------------------
# Instances


#: Decides, per member, a value that replaces everything else (used for YAML overrides).
OverrideHook = Callable[[str, "TypedExpr | None", "FieldInfo"], "TypedExpr | None"]


class FieldInfo:
    """What an override hook needs to know about a member."""

    __slots__ = ("name", "type", "default", "is_field", "location")

    def __init__(self, name: str, type_: OscType, default: syntax.Expression | None, is_field: bool,
                 location: Location) -> None:
        self.name, self.type, self.default, self.is_field, self.location = name, type_, default, is_field, location


def instantiate(ctx: ResolveContext, ctype: CompoundType, given: dict[str, TypedExpr], keeps: list[KeepValue],
                prefix: str, location: Location, scope_names: dict[str, TypedExpr] | None = None,
                override: OverrideHook | None = None, outer: Scope | None = None) -> TypedExpr:
    """A value of ``ctype``; ``prefix`` names it (variable keys are ``prefix.member``).

    ``scope_names`` (when given) receives every member as it is computed, so the caller can use the
    members as names afterwards (a scenario's parameters and variables).
    """
    if ctype.name in ctx.building:
        chain = " → ".join([*ctx.building[ctx.building.index(ctype.name):], ctype.name])
        raise ResolveError(f"{ctype.kind} '{ctype.name}' contains itself ({chain}); give the member a "
                           "default or make it a list", location)
    ctx.building.append(ctype.name)
    try:
        return _instantiate(ctx, ctype, given, keeps, prefix, location, scope_names, override, outer)
    finally:
        ctx.building.pop()


def _instantiate(ctx: ResolveContext, ctype: CompoundType, given: dict[str, TypedExpr], keeps: list[KeepValue],
                 prefix: str, location: Location, scope_names: dict[str, TypedExpr] | None,
                 override: OverrideHook | None, outer: Scope | None) -> TypedExpr:
    type_scope = Scope(ctx) if outer is None else outer.child()
    type_keeps, checks = split_type_keeps(ctype, type_scope)
    all_keeps = type_keeps + list(keeps)
    direct: dict[str, list[KeepValue]] = {}
    nested: dict[str, list[KeepValue]] = {}
    for keep in all_keeps:
        if not keep.path:
            raise ResolveError(f"'keep(it == …)' cannot replace a whole '{ctype.name}' here; "
                               "constrain a member ('keep(it.member == …)')", keep.location)
        head = keep.path[0]
        if head not in ctype.fields and head not in ctype.variables:
            raise NameLookupError(f"'{ctype.name}' has no member '{head}'", keep.location)
        if len(keep.path) == 1:
            direct.setdefault(head, []).append(keep)
        else:
            nested.setdefault(head, []).append(
                KeepValue(keep.path[1:], keep.value, keep.scope, keep.location, keep.is_default))
    values: dict[str, TypedExpr] = scope_names if scope_names is not None else {}
    member_scope = type_scope.child(values)
    for name, fdecl in ctype.fields.items():
        key = f"{prefix}.{name}" if prefix else name
        value = given.get(name)
        if value is not None:
            value = coerce(value, fdecl.type, fdecl.location, f"member '{name}'")
        if name in direct:
            value = _kept_value(ctype, name, fdecl.type, value, direct[name])
        if value is None:
            value = field_value(ctx, fdecl.type, fdecl.default, fdecl.with_members, member_scope, key,
                                fdecl.location, f"member '{name}'", check=False)
        if name in nested:
            value = apply_nested_keeps(ctx, value, nested[name], key, fdecl.location)
        if override is not None:
            value = override(name, value, FieldInfo(name, fdecl.type, fdecl.default, True, fdecl.location)) or value
        for condition in split_with_keeps(fdecl.with_members, member_scope)[1]:   # on the final value
            check_keep(condition, {}, value, resolve_expression)
        values[name] = value
    for name, vdecl in ctype.variables.items():
        key = f"{prefix}.{name}" if prefix else name
        if override is not None:
            override(name, None, FieldInfo(name, vdecl.type, vdecl.initial, False, vdecl.location))
        if name in nested:
            raise UnsupportedFeatureError(f"not supported: 'keep' on members of variable '{name}'",
                                          nested[name][0].location)
        if name in direct:  # a keep on a variable sets its initial value
            kept = _kept_value(ctype, name, vdecl.type, None, direct[name])
            assert kept is not None  # direct[name] holds at least one keep
            initial = kept
        else:
            initial = field_value(ctx, vdecl.type, vdecl.initial, (), member_scope, key, vdecl.location,
                                  f"variable '{name}'")
        variable = model.Variable(key, vdecl.type.name, initial.expr, vdecl.location)
        ctx.variables.append(variable)
        values[name] = TypedExpr(model.VariableRef(variable), vdecl.type, False)
    value = struct_value(ctype, values)
    for check in checks:             # conditions on the members, once every member has its value
        check_keep(check, values, value, resolve_expression)
    return value


def _kept_value(ctype: CompoundType, name: str, mtype: OscType, given: TypedExpr | None,
                keeps: list[KeepValue]) -> TypedExpr | None:
    """The value the keeps on member ``name`` fix, checked against a given value and each other.

    A hard ``keep(it.x == v)`` is a constraint, not a default: two that fix different constants (or
    one that disagrees with a constructor argument) are an error. ``keep(default …)`` only applies
    when nothing else gives a value; the last one written wins.
    """
    hard = [k for k in keeps if not k.is_default]
    chosen = given
    for keep in hard:
        value = coerce(resolve_expression(keep.value, keep.scope, mtype), mtype, keep.location, f"keep of '{name}'",
                       unit_required=True)
        if chosen is not None and chosen.is_const and value.is_const and chosen.value != value.value:
            raise ResolveError(f"contradicting constraints on '{ctype.name}.{name}': {chosen.value!r} and "
                               f"{value.value!r}", keep.location)
        if chosen is None:
            chosen = value
    if chosen is None:
        soft = [k for k in keeps if k.is_default]
        if soft:
            keep = soft[-1]
            chosen = coerce(resolve_expression(keep.value, keep.scope, mtype), mtype, keep.location,
                            f"keep of '{name}'", unit_required=True)
    return chosen


def field_value(ctx: ResolveContext, ftype: OscType, default: syntax.Expression | None, with_members: tuple,
                scope: Scope, key: str, location: Location, what: str, *, check: bool = True) -> TypedExpr:
    """The value of a member or global from its default (or its type's zero), with its ``with:`` keeps.

    ``check``: also check the ``with:`` conditions (``keep(it >= 2m)``) on it; a caller that may still
    replace the value (a parameter override) passes False and checks the final value itself.
    """
    keeps, checks = split_with_keeps(with_members, scope)
    for m in with_members:
        if isinstance(m, (syntax.ModifierInvocation, syntax.Until)):
            raise ResolveError(f"a modifier cannot be applied to {what}", m.location)
    value = _field_value(ctx, ftype, default, keeps, scope, key, location, what)
    for condition in checks if check else ():     # keep(it >= 2m): a condition on the value itself
        check_keep(condition, {}, value, resolve_expression)
    return value



def _field_value(ctx: ResolveContext, ftype: OscType, default: syntax.Expression | None, keeps: list[KeepValue],
                 scope: Scope, key: str, location: Location, what: str) -> TypedExpr:
    whole = [k for k in keeps if not k.path]
    if whole:
        # ``p: T with: keep(it == v)`` gives the value itself; the last such keep wins over the default.
        keeps = [k for k in keeps if k.path]
        value = coerce(resolve_expression(whole[-1].value, whole[-1].scope, ftype), ftype, whole[-1].location, what,
                       unit_required=True)
        return apply_nested_keeps(ctx, value, keeps, key, location) if keeps else value
    if default is not None:
        value = coerce(resolve_expression(default, scope, ftype), ftype, default.location, what, unit_required=True)
        if keeps:
            value = apply_nested_keeps(ctx, value, keeps, key, location)
        return value
    if isinstance(ftype, CompoundType):
        return instantiate(ctx, ftype, {}, keeps, key, location)
    if keeps:
        raise ResolveError(f"{what}: 'keep(it…)' needs a struct or actor type, not {ftype}", keeps[0].location)
    return TypedExpr(model.Const(zero_value(ftype)), ftype, True)


def apply_nested_keeps(ctx: ResolveContext, value: TypedExpr, keeps: list[KeepValue], key: str,
                       location: Location) -> TypedExpr:
    """Replace members of an already built instance as ``keeps`` say (paths relative to the instance)."""
    ctype = value.type
    if not isinstance(ctype, CompoundType):
        raise ResolveError(f"'keep(it…)' needs a struct or actor value, not {ctype}", keeps[0].location)
    members = members_of(value)
    for keep in keeps:
        head = keep.path[0]
        fdecl = ctype.fields.get(head)
        if fdecl is None:
            raise NameLookupError(f"'{ctype.name}' has no member '{head}'", keep.location)
        if len(keep.path) == 1:
            new = resolve_expression(keep.value, keep.scope, fdecl.type)
            members[head] = coerce(new, fdecl.type, keep.location, f"keep of '{head}'", unit_required=True)
        else:
            sub = KeepValue(keep.path[1:], keep.value, keep.scope, keep.location, keep.is_default)
            members[head] = apply_nested_keeps(ctx, members[head], [sub], f"{key}.{head}", location)
    return struct_value(ctype, members)


def construct(ctx: ResolveContext, ctype: CompoundType, arguments: tuple[syntax.Argument, ...], scope: Scope,
              location: Location) -> TypedExpr:
    """``type(args)``: a struct built from constructor arguments (positional in member order, or named)."""
    bound = bind_arguments(list(ctype.fields), arguments, f"'{ctype.name}(...)'", location)
    given = {name: coerce(resolve_expression(arg.value, scope, ctype.fields[name].type), ctype.fields[name].type,
                          arg.location, f"'{ctype.name}(...)', argument '{name}'")
             for name, arg in bound.items()}
    value = instantiate(ctx, ctype, given, [], ctx.fresh_path(ctype.name), location)
    literal = all(v.is_literal for v in given.values())
    return TypedExpr(value.expr, value.type, literal)


def global_value(ctx: ResolveContext, name: str, location: Location) -> TypedExpr:
    """The value of ``global name``, computed once; a global that needs itself is an error."""
    found = ctx.global_values.get(name)
    if found is not None:
        return found
    if name in ctx.globals_in_progress:
        raise ResolveError(f"global '{name}' depends on itself", location)
    decl = ctx.namespace.globals[name]
    ctx.globals_in_progress.append(name)
    try:
        gtype = ctx.namespace.lookup_type(decl.type)
        value = field_value(ctx, gtype, decl.default, decl.with_members, Scope(ctx), name, decl.location,
                            f"global '{name}'")
    finally:
        ctx.globals_in_progress.remove(name)
    ctx.global_values[name] = value
    return value


# --------------------------------------------------------------------------------------------------
# External methods


def external_method(ctx: ResolveContext, decl: syntax.MethodDecl, owner: CompoundType) -> model.ExternalMethod:
    """The model signature of ``decl`` (built once per resolution)."""
    found = ctx.methods.get(id(decl))
    if found is not None:
        return found
    parts = decl.external.parts
    if len(parts) < 2:
        raise ResolveError(f"external method '{decl.name}': '{decl.external.dotted}' is not a "
                           "'module.function' path", decl.external.location)
    if decl.external_arguments:
        raise ResolveError(f"external method '{decl.name}': arguments in the 'external' call are not supported",
                           decl.external.location)
    scope = Scope(ctx)
    params = []
    for p in decl.parameters:
        ptype = ctx.namespace.lookup_type(p.type)
        default = None
        if p.default is not None:
            default = coerce(resolve_expression(p.default, scope, ptype), ptype, p.default.location,
                             f"default of '{p.name}'", unit_required=True).expr
        params.append((p.name, ptype.name, default))
    return_type = ctx.namespace.lookup_type(decl.return_type).name if decl.return_type is not None else None
    method = model.ExternalMethod(f"{owner.name}.{decl.name}", ".".join(parts[:-1]), parts[-1], tuple(params),
                                  return_type, decl.location)
    ctx.methods[id(decl)] = method
    return method


def call_external(ctx: ResolveContext, decl: syntax.MethodDecl, owner: CompoundType,
                  arguments: tuple[syntax.Argument, ...], scope: Scope, location: Location) -> TypedExpr:
    """A checked call of an external method."""
    method = external_method(ctx, decl, owner)
    names = [p.name for p in decl.parameters]
    bound = bind_arguments(names, arguments, f"method '{method.name}'", location)
    values: list[tuple[str, model.Expr]] = []
    for p, (name, _tname, default) in zip(decl.parameters, method.parameters, strict=True):
        ptype = ctx.namespace.lookup_type(p.type)
        if name in bound:
            arg = bound[name]
            value = coerce(resolve_expression(arg.value, scope, ptype), ptype, arg.location, f"argument '{name}'")
            values.append((name, value.expr))
        elif default is not None:
            values.append((name, default))
        else:
            raise ArgumentError(f"method '{method.name}': missing argument '{name}'", location)
    rtype = ctx.namespace.lookup_type(decl.return_type) if decl.return_type is not None else ANY
    return TypedExpr(model.ExternalCall(method, tuple(values), location), rtype, False)
