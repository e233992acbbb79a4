"""Resolve instances: the value of a struct, actor or scenario, of each of its members, and of a global.

A member's value comes from, in order: an argument given to the constructor (or a parameter
override), a ``keep(it.member == v)`` on the instance, a ``keep`` written in the type, the member's
default, and finally the zero value of its type (a default-built instance for struct types). ``var``
members become :class:`~coverage_engine.resolve.model.Variable` s keyed by their path.

Defaults, keeps and constructor arguments are expressions: they are resolved through
:attr:`ResolveContext.resolve_expression <coverage_engine.resolve.scope.ResolveContext>`, since the
expression resolver (:mod:`~coverage_engine.resolve.expressions`) builds instances itself and imports
this module.
"""

from __future__ import annotations

from collections.abc import Callable

from coverage_engine.errors import NameLookupError, ResolveError, UnsupportedFeatureError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve import model
from coverage_engine.resolve.keeps import check_keep, split_type_keeps, split_with_keeps
from coverage_engine.resolve.operations import bind_arguments, coerce, members_of, struct_value
from coverage_engine.resolve.scope import KeepValue, ResolveContext, Scope, TypedExpr
from coverage_engine.resolve.types import CompoundType, OscType, zero_value

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
    direct, nested = _keeps_by_member(ctype, type_keeps + list(keeps))
    values: dict[str, TypedExpr] = scope_names if scope_names is not None else {}
    member_scope = type_scope.child(values)
    for name, fdecl in ctype.fields.items():
        key = f"{prefix}.{name}" if prefix else name
        value = given.get(name)
        if value is not None:
            value = coerce(value, fdecl.type, fdecl.location, f"member '{name}'")
        if name in direct:
            value = _kept_value(ctx, ctype, name, fdecl.type, value, direct[name])
        if value is None:
            value = field_value(ctx, fdecl.type, fdecl.default, fdecl.with_members, member_scope, key,
                                fdecl.location, f"member '{name}'", check=False)
        if name in nested:
            value = apply_nested_keeps(ctx, value, nested[name], key, fdecl.location)
        if override is not None:
            value = override(name, value, FieldInfo(name, fdecl.type, fdecl.default, True, fdecl.location)) or value
        for condition in split_with_keeps(fdecl.with_members, member_scope)[1]:   # on the final value
            check_keep(condition, {}, value, ctx.resolve_expression)
        values[name] = value
    for name, vdecl in ctype.variables.items():
        if override is not None:
            override(name, None, FieldInfo(name, vdecl.type, vdecl.initial, False, vdecl.location))
        if name in nested:
            raise UnsupportedFeatureError(f"not supported: 'keep' on members of variable '{name}'",
                                          nested[name][0].location)
        values[name] = _variable(ctx, ctype, name, f"{prefix}.{name}" if prefix else name, direct.get(name),
                                 member_scope)
    value = struct_value(ctype, values)
    for check in checks:             # conditions on the members, once every member has its value
        check_keep(check, values, value, ctx.resolve_expression)
    return value


def _keeps_by_member(ctype: CompoundType,
                     keeps: list[KeepValue]) -> tuple[dict[str, list[KeepValue]], dict[str, list[KeepValue]]]:
    """The keeps on an instance of ``ctype`` by the member they fix: those on the member itself
    (``it.speed``) and those on a member of it (``it.pose.x``, its path then relative to the member)."""
    direct: dict[str, list[KeepValue]] = {}
    nested: dict[str, list[KeepValue]] = {}
    for keep in keeps:
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
    return direct, nested


def _variable(ctx: ResolveContext, ctype: CompoundType, name: str, key: str, keeps: list[KeepValue] | None,
              scope: Scope) -> TypedExpr:
    """The ``var`` member ``name`` of an instance: a new run-time variable (keyed ``key``) whose initial
    value a keep on it sets, else its declared initial value or its type's zero."""
    vdecl = ctype.variables[name]
    if keeps:  # a keep on a variable sets its initial value
        kept = _kept_value(ctx, ctype, name, vdecl.type, None, keeps)
        assert kept is not None  # keeps holds at least one keep
        initial = kept
    else:
        initial = field_value(ctx, vdecl.type, vdecl.initial, (), scope, key, vdecl.location, f"variable '{name}'")
    variable = model.Variable(key, vdecl.type.name, initial.expr, vdecl.location)
    ctx.variables.append(variable)
    return TypedExpr(model.VariableRef(variable), vdecl.type, False)


def _kept_value(ctx: ResolveContext, ctype: CompoundType, name: str, mtype: OscType, given: TypedExpr | None,
                keeps: list[KeepValue]) -> TypedExpr | None:
    """The value the keeps on member ``name`` fix, checked against a given value and each other.

    A hard ``keep(it.x == v)`` is a constraint, not a default: two that fix different constants (or
    one that disagrees with a constructor argument) are an error. ``keep(default …)`` only applies
    when nothing else gives a value; the last one written wins.
    """
    hard = [k for k in keeps if not k.is_default]
    chosen = given
    for keep in hard:
        value = coerce(ctx.resolve_expression(keep.value, keep.scope, mtype), mtype, keep.location, f"keep of '{name}'",
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
            chosen = coerce(ctx.resolve_expression(keep.value, keep.scope, mtype), mtype, keep.location,
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
        check_keep(condition, {}, value, ctx.resolve_expression)
    return value



def _field_value(ctx: ResolveContext, ftype: OscType, default: syntax.Expression | None, keeps: list[KeepValue],
                 scope: Scope, key: str, location: Location, what: str) -> TypedExpr:
    whole = [k for k in keeps if not k.path]
    if whole:
        # ``p: T with: keep(it == v)`` gives the value itself; the last such keep wins over the default.
        keeps = [k for k in keeps if k.path]
        value = coerce(ctx.resolve_expression(whole[-1].value, whole[-1].scope, ftype), ftype, whole[-1].location, what,
                       unit_required=True)
        return apply_nested_keeps(ctx, value, keeps, key, location) if keeps else value
    if default is not None:
        value = coerce(ctx.resolve_expression(default, scope, ftype), ftype, default.location, what, unit_required=True)
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
            new = ctx.resolve_expression(keep.value, keep.scope, fdecl.type)
            members[head] = coerce(new, fdecl.type, keep.location, f"keep of '{head}'", unit_required=True)
        else:
            sub = KeepValue(keep.path[1:], keep.value, keep.scope, keep.location, keep.is_default)
            members[head] = apply_nested_keeps(ctx, members[head], [sub], f"{key}.{head}", location)
    return struct_value(ctype, members)


def construct(ctx: ResolveContext, ctype: CompoundType, arguments: tuple[syntax.Argument, ...], scope: Scope,
              location: Location) -> TypedExpr:
    """``type(args)``: a struct built from constructor arguments (positional in member order, or named)."""
    bound = bind_arguments(list(ctype.fields), arguments, f"'{ctype.name}(...)'", location)
    given = {name: coerce(ctx.resolve_expression(arg.value, scope, ctype.fields[name].type), ctype.fields[name].type,
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

