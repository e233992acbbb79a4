"""Build struct, actor and scenario instances: given values, then ``keep`` constraints, then defaults.

A member's value comes from, in order: an argument given to the constructor (or a parameter
override), a ``keep(it.member == v)`` on the instance, a ``keep`` written in the type, the member's
default, and finally the zero value of its type (a default-built instance for struct types).
``var`` members become :class:`~coverage_engine.resolve.model.Variable` s keyed by their path.
"""

from __future__ import annotations

from collections.abc import Callable

from coverage_engine.errors import NameLookupError, ResolveError, UnsupportedFeatureError
from coverage_engine.parse import syntax
from coverage_engine.resolve import model
from coverage_engine.resolve.expressions import bind_arguments, coerce, resolve_expression
from coverage_engine.resolve.scope import KeepValue, ResolveContext, Scope, TypedExpr
from coverage_engine.resolve.types import CompoundType, OscType, zero_value

#: Decides, per member, a value that replaces everything else (used for YAML overrides).
OverrideHook = Callable[[str, "TypedExpr | None", "FieldInfo"], "TypedExpr | None"]


def it_path(expr: syntax.Expression) -> tuple[str, ...] | None:
    """``it.a.b`` → ``("a", "b")``; ``it`` → ``()``; a bare member name ``a`` → ``("a",)``; else None."""
    parts: list[str] = []
    while isinstance(expr, syntax.MemberAccess):
        parts.append(expr.member)
        expr = expr.target
    if isinstance(expr, syntax.Identifier):
        if expr.name == "it":
            return tuple(reversed(parts))
        return (expr.name, *reversed(parts))
    return None


def extract_keep(keep: syntax.KeepConstraint, scope: Scope) -> KeepValue:
    """Reduce ``keep(it.path == value)`` to a :class:`KeepValue`; other relations are not supported."""
    expr = keep.expression
    if isinstance(expr, syntax.BinaryOp):
        path = it_path(expr.left)
        if path is not None and expr.op == "==":
            return KeepValue(path, expr.right, scope, keep.location, keep.is_default)
        if path is not None and expr.op == "in":
            raise UnsupportedFeatureError(
                "not supported: 'keep(... in [...])' when running a scenario; expand it into concrete "
                "scenarios with scenario_variation", keep.location)
        if path is not None:
            raise UnsupportedFeatureError(f"not supported: keep with the relation '{expr.op}' "
                                          "(only 'keep(it.member == value)')", keep.location)
    raise UnsupportedFeatureError("not supported: this keep constraint (only 'keep(it.member == value)')",
                                  keep.location)


class FieldInfo:
    """What an override hook needs to know about a member."""

    __slots__ = ("name", "type", "default", "is_field", "location")

    def __init__(self, name: str, type_: OscType, default: syntax.Expression | None, is_field: bool,
                 location: syntax.Location) -> None:
        self.name, self.type, self.default, self.is_field, self.location = name, type_, default, is_field, location


def instantiate(ctx: ResolveContext, ctype: CompoundType, given: dict[str, TypedExpr], keeps: list[KeepValue],
                prefix: str, location: syntax.Location, scope_names: dict[str, TypedExpr] | None = None,
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
                 prefix: str, location: syntax.Location, scope_names: dict[str, TypedExpr] | None,
                 override: OverrideHook | None, outer: Scope | None) -> TypedExpr:
    type_scope = Scope(ctx) if outer is None else outer.child()
    all_keeps = [extract_keep(k, type_scope) for k in ctype.keeps] + list(keeps)
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
                                fdecl.location, f"member '{name}'")
        if name in nested:
            value = apply_nested_keeps(ctx, value, nested[name], key, fdecl.location)
        if override is not None:
            value = override(name, value, FieldInfo(name, fdecl.type, fdecl.default, True, fdecl.location)) or value
        values[name] = value
    for name, vdecl in ctype.variables.items():
        key = f"{prefix}.{name}" if prefix else name
        if override is not None:
            override(name, None, FieldInfo(name, vdecl.type, vdecl.initial, False, vdecl.location))
        if name in nested:
            raise UnsupportedFeatureError(f"not supported: 'keep' on members of variable '{name}'",
                                          nested[name][0].location)
        if name in direct:  # a keep on a variable sets its initial value
            initial = _kept_value(ctype, name, vdecl.type, None, direct[name])
        else:
            initial = field_value(ctx, vdecl.type, vdecl.initial, (), member_scope, key, vdecl.location,
                                  f"variable '{name}'")
        variable = model.Variable(key, vdecl.type.name, initial.expr, vdecl.location)
        ctx.variables.append(variable)
        values[name] = TypedExpr(model.VariableRef(variable), vdecl.type, False)
    return struct_value(ctype, values)


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
        value = coerce(resolve_expression(keep.value, keep.scope, mtype), mtype, keep.location, f"keep of '{name}'")
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
                            f"keep of '{name}'")
    return chosen


def struct_value(ctype: CompoundType, values: dict[str, TypedExpr]) -> TypedExpr:
    """Fold member values into one ``dict`` constant when all are known, else a MakeStruct."""
    literal = all(v.is_literal for v in values.values())
    if all(v.is_const for v in values.values()):
        return TypedExpr(model.Const({k: v.value for k, v in values.items()}), ctype, literal)
    return TypedExpr(model.MakeStruct(ctype.name, tuple((k, v.expr) for k, v in values.items())), ctype, literal)


def field_value(ctx: ResolveContext, ftype: OscType, default: syntax.Expression | None, with_members: tuple,
                scope: Scope, key: str, location: syntax.Location, what: str) -> TypedExpr:
    """The value of a member or global from its default (or its type's zero), with its ``with:`` keeps."""
    keeps = [extract_keep(k, scope) for k in with_members if isinstance(k, syntax.KeepConstraint)]
    for m in with_members:
        if isinstance(m, syntax.ModifierInvocation):
            raise ResolveError(f"a modifier cannot be applied to {what}", m.location)
    whole = [k for k in keeps if not k.path]
    if whole:
        # ``p: T with: keep(it == v)`` gives the value itself; the last such keep wins over the default.
        keeps = [k for k in keeps if k.path]
        value = coerce(resolve_expression(whole[-1].value, whole[-1].scope, ftype), ftype, whole[-1].location, what)
        return apply_nested_keeps(ctx, value, keeps, key, location) if keeps else value
    if default is not None:
        value = coerce(resolve_expression(default, scope, ftype), ftype, default.location, what)
        if keeps:
            value = apply_nested_keeps(ctx, value, keeps, key, location)
        return value
    if isinstance(ftype, CompoundType):
        return instantiate(ctx, ftype, {}, keeps, key, location)
    if keeps:
        raise ResolveError(f"{what}: 'keep(it…)' needs a struct or actor type, not {ftype}", keeps[0].location)
    return TypedExpr(model.Const(zero_value(ftype)), ftype, True)


def apply_nested_keeps(ctx: ResolveContext, value: TypedExpr, keeps: list[KeepValue], key: str,
                       location: syntax.Location) -> TypedExpr:
    """Replace members of an already built instance as ``keeps`` say (paths relative to the instance)."""
    ctype = value.type
    if not isinstance(ctype, CompoundType):
        raise ResolveError(f"'keep(it…)' needs a struct or actor value, not {ctype}", keeps[0].location)
    members = _members_of(value)
    for keep in keeps:
        head = keep.path[0]
        fdecl = ctype.fields.get(head)
        if fdecl is None:
            raise NameLookupError(f"'{ctype.name}' has no member '{head}'", keep.location)
        if len(keep.path) == 1:
            new = resolve_expression(keep.value, keep.scope, fdecl.type)
            members[head] = coerce(new, fdecl.type, keep.location, f"keep of '{head}'")
        else:
            sub = KeepValue(keep.path[1:], keep.value, keep.scope, keep.location, keep.is_default)
            members[head] = apply_nested_keeps(ctx, members[head], [sub], f"{key}.{head}", location)
    return struct_value(ctype, members)


def _members_of(value: TypedExpr) -> dict[str, TypedExpr]:
    ctype = value.type
    assert isinstance(ctype, CompoundType)
    types = {n: f.type for n, f in ctype.fields.items()} | {n: v.type for n, v in ctype.variables.items()}
    expr = value.expr
    if isinstance(expr, model.Const) and isinstance(expr.value, dict):
        return {k: TypedExpr(model.Const(v), types.get(k, ctype), value.is_literal) for k, v in expr.value.items()}
    if isinstance(expr, model.MakeStruct):
        return {k: TypedExpr(v, types.get(k, ctype), False) for k, v in expr.members}
    return {k: TypedExpr(model.FieldOf(expr, k), t, False) for k, t in types.items()}


def construct(ctx: ResolveContext, ctype: CompoundType, arguments: tuple[syntax.Argument, ...], scope: Scope,
              location: syntax.Location) -> TypedExpr:
    """``type(args)``: a struct built from constructor arguments (positional in member order, or named)."""
    bound = bind_arguments(list(ctype.fields), arguments, f"'{ctype.name}(...)'", location)
    given = {name: coerce(resolve_expression(arg.value, scope, ctype.fields[name].type), ctype.fields[name].type,
                          arg.location, f"'{ctype.name}(...)', argument '{name}'")
             for name, arg in bound.items()}
    value = instantiate(ctx, ctype, given, [], ctx.fresh_path(ctype.name), location)
    literal = all(v.is_literal for v in given.values())
    return TypedExpr(value.expr, value.type, literal)


def global_value(ctx: ResolveContext, name: str, location: syntax.Location) -> TypedExpr:
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
