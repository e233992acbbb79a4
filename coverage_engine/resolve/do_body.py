"""Resolve a ``do`` body into model behaviours: composites, action calls, waits, emits and modifiers.

Modifiers written among a composite's members (``repeat()`` inside ``serial:``) or in a ``with:``
block apply to that composite or invocation; several nest in the order written, the first outermost
(``retry(3)`` above ``timeout(2s)`` retries the timed-out attempt).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import cast

from coverage_engine.errors import (
    ArgumentError,
    NameLookupError,
    OscTypeError,
    ResolveError,
    UnsupportedFeatureError,
)
from coverage_engine.parse import syntax
from coverage_engine.records import replace
from coverage_engine.resolve import model
from coverage_engine.resolve.expressions import resolve_expression
from coverage_engine.resolve.instances import apply_nested_keeps, instantiate
from coverage_engine.resolve.keeps import KeepCheck, check_keep, classify_keep
from coverage_engine.resolve.operations import bind_arguments, coerce, struct_value
from coverage_engine.resolve.scope import KeepValue, Scope, TypedExpr
from coverage_engine.resolve.types import (
    ANY,
    BOOL,
    CompoundType,
    FieldDecl,
    ListType,
    PhysicalType,
    is_numeric,
)


def resolve_behavior(node: syntax.Behavior, scope: Scope) -> model.Behavior:
    """The model behaviour for one member of a ``do`` body."""
    if isinstance(node, syntax.Composite):
        return _composite(node, scope)
    if isinstance(node, syntax.Invocation):
        return _invocation(node, scope)
    if isinstance(node, syntax.Wait):
        return _wait(node, scope)
    if isinstance(node, syntax.Emit):
        return _emit(node, scope)
    if isinstance(node, syntax.CallDirective):
        call = resolve_expression(node.call, scope)
        return model.CallMethod(node.label or "call", call.expr, node.location)
    if isinstance(node, syntax.ModifierInvocation):
        raise ResolveError(f"modifier '{node.name.dotted}' must stand inside a composite or a 'with:' block",
                           node.location)
    raise ResolveError(f"unexpected {type(node).__name__} in a 'do' body", getattr(node, "location", None))


def modifier_type(name: syntax.QualifiedName, scope: Scope) -> CompoundType | None:
    """The modifier declaration ``name`` refers to, if it names one."""
    found = scope.ctx.namespace.types.get(name.dotted)
    if isinstance(found, CompoundType) and found.kind == "modifier":
        return found
    return None


def _composite(node: syntax.Composite, scope: Scope) -> model.Behavior:
    if node.arguments:
        raise UnsupportedFeatureError(f"not supported: arguments of '{node.kind}'", node.location)
    children: list[model.Behavior] = []
    modifiers: list[syntax.ModifierInvocation] = []
    for member in node.members:
        if isinstance(member, syntax.ModifierInvocation):
            modifiers.append(member)
        elif isinstance(member, syntax.Invocation) and not member.with_members and member.label is None \
                and modifier_type(member.name, scope) is not None:
            modifiers.append(syntax.ModifierInvocation(member.name, member.arguments, member.location))
        else:
            children.append(resolve_behavior(member, scope))
    untils = []
    for extra in node.with_members:
        if isinstance(extra, syntax.KeepConstraint):
            raise ResolveError(f"'keep' cannot constrain a '{node.kind}'", extra.location)
        if isinstance(extra, syntax.CoverageDecl):
            raise _coverage_misplaced(extra)
        if isinstance(extra, syntax.Until):
            untils.append(extra)
            continue
        modifiers.append(extra)
    composite = model.Composite(node.kind, node.label or node.kind, tuple(children), node.location)
    return apply_until(apply_modifiers(composite, modifiers, scope), untils, scope)


def apply_modifiers(behavior: model.Behavior, modifiers: list[syntax.ModifierInvocation],
                    scope: Scope) -> model.Behavior:
    """Wrap ``behavior`` in each modifier, the first written outermost."""
    for invocation in reversed(modifiers):
        mtype = modifier_type(invocation.name, scope)
        if mtype is None:
            raise NameLookupError(f"unknown modifier '{invocation.name.dotted}'", invocation.name.location)
        what = f"modifier '{mtype.name}'"
        bound = bind_arguments(list(mtype.fields), invocation.arguments, what, invocation.location)
        arguments: list[tuple[str, object]] = []
        for name, fdecl in mtype.fields.items():
            if name in bound:
                arg = bound[name]
                value = coerce(resolve_expression(arg.value, scope, fdecl.type), fdecl.type, arg.location,
                               f"{what}, argument '{name}'")
            elif fdecl.default is not None:
                value = coerce(resolve_expression(fdecl.default, Scope(scope.ctx), fdecl.type), fdecl.type,
                               fdecl.location, f"{what}, parameter '{name}'", unit_required=True)
            else:
                raise ArgumentError(f"{what}: missing argument '{name}'", invocation.location)
            if not value.is_const:
                raise ResolveError(f"{what}: argument '{name}' must be known before the run", invocation.location)
            arguments.append((name, value.value))
        _check_modifier_arguments(mtype.name, dict(arguments), invocation)
        behavior = model.Modified(mtype.name, tuple(arguments), behavior, invocation.location)
    return behavior


def _check_modifier_arguments(name: str, arguments: dict[str, object], invocation: syntax.ModifierInvocation) -> None:
    """Reject argument values of the built-in modifiers that cannot mean anything (``repeat(-3)``)."""
    count = arguments.get("count")
    if name == "repeat" and isinstance(count, int) and count < -1:
        raise ArgumentError(f"repeat({count}): the count is a number of runs, or -1 for no end", invocation.location)
    if name == "retry" and isinstance(count, int) and count < 0:
        raise ArgumentError(f"retry({count}): the count of permitted failures cannot be negative",
                            invocation.location)
    duration = arguments.get("duration")
    if name == "timeout" and isinstance(duration, (int, float)) and not (0 < duration < math.inf):
        raise ArgumentError(f"timeout({duration} s): the duration must be a positive time", invocation.location)


def _find_action(node: syntax.Invocation, scope: Scope) -> tuple[CompoundType, model.Expr | None]:
    parts = node.name.parts
    types = scope.ctx.namespace.types
    if len(parts) > 1:
        instance = scope.lookup(parts[0])
        if instance is not None and len(parts) == 2:
            if not isinstance(instance.type, CompoundType) or instance.type.kind != "actor":
                raise OscTypeError(f"'{parts[0]}' is not an actor, so it has no action '{parts[1]}'",
                                   node.name.location)
            for ancestor in instance.type.ancestry():
                if parts[1] in ancestor.behaviors:
                    return ancestor.behaviors[parts[1]], _named_actor(instance.expr, parts[0])
            raise NameLookupError(f"actor '{instance.type.name}' has no action '{parts[1]}'", node.name.location)
        if parts[0] not in types and instance is None:
            raise NameLookupError(f"unknown actor '{parts[0]}'", node.name.location)
    found = types.get(node.name.dotted)
    if isinstance(found, CompoundType):
        if found.kind == "action":
            return found, None
        if found.kind == "modifier":
            raise ResolveError(f"modifier '{found.name}' cannot be used as a behaviour here", node.location)
        if found.kind == "scenario":
            raise UnsupportedFeatureError(f"not supported: invoking scenario '{found.name}'", node.location)
    raise NameLookupError(f"unknown action '{node.name.dotted}'", node.name.location)


def _named_actor(actor: model.Expr, name: str) -> model.Expr:
    """The actor instance as an action receives it: its members plus ``name`` (the instance's name)."""
    if isinstance(actor, model.Const) and isinstance(actor.value, dict):
        return model.Const({**actor.value, "name": name})
    if isinstance(actor, model.MakeStruct):
        return model.MakeStruct(actor.type_name, (*actor.members, ("name", model.Const(name))))
    return actor


def _invocation(node: syntax.Invocation, scope: Scope) -> model.Behavior:
    action, actor = _find_action(node, scope)
    what = f"action '{action.name}'"
    bound = bind_arguments(list(action.fields), node.arguments, what, node.location)
    members = _with_members(node, action, bound, scope, what)
    arguments: list[tuple[str, model.Expr]] = []
    values: dict[str, TypedExpr] = {}
    for name, fdecl in action.fields.items():
        value = _argument(name, fdecl, bound, members, node, scope, what)
        arguments.append((name, value.expr))
        values[name] = value
    if members.conditions:
        instance = struct_value(action, values)
        for condition in members.conditions:
            check_keep(condition, {}, instance, resolve_expression)
    plugin_names = tuple(t.name for t in action.ancestry())
    call = model.ActionCall(action.name, plugin_names, node.label or node.name.parts[-1], tuple(arguments), actor,
                            node.location, node.label is not None)
    return apply_until(apply_modifiers(call, members.modifiers, scope), members.untils, scope)


@dataclass(frozen=True)
class _WithMembers:
    """An invocation's ``with:`` block sorted by what each member does to the action call."""

    #: ``keep(it.speed == 1mps)``: the value of a parameter, by its name.
    keeps: dict[str, KeepValue]
    #: ``keep(it.pose.position.x == 1m)``: part of a struct parameter (paths below the parameter).
    nested: dict[str, list[KeepValue]]
    modifiers: list[syntax.ModifierInvocation]
    untils: list[syntax.Until]
    #: ``keep(it.speed > 1mps)``: checked once the arguments are known.
    conditions: list[KeepCheck]


def _with_members(node: syntax.Invocation, action: CompoundType, bound: dict[str, syntax.Argument], scope: Scope,
                  what: str) -> _WithMembers:
    """Sort ``node``'s ``with:`` members; a keep naming no parameter, or one already given, is an error."""
    keeps: dict[str, KeepValue] = {}
    nested: dict[str, list[KeepValue]] = {}
    modifiers: list[syntax.ModifierInvocation] = []
    untils: list[syntax.Until] = []
    conditions: list[KeepCheck] = []
    for member in node.with_members:
        if isinstance(member, syntax.ModifierInvocation):
            modifiers.append(member)
            continue
        if isinstance(member, syntax.CoverageDecl):
            raise _coverage_misplaced(member)
        if isinstance(member, syntax.Until):
            untils.append(member)
            continue
        found = classify_keep(member, scope)
        if isinstance(found, KeepCheck):
            conditions.append(found)
            continue
        keep = found
        if len(keep.path) > 1 and keep.path[0] in action.fields \
                and isinstance(action.fields[keep.path[0]].type, CompoundType):
            nested.setdefault(keep.path[0], []).append(replace(keep, path=keep.path[1:]))
            continue
        if len(keep.path) != 1 or keep.path[0] not in action.fields:
            if not keep.path:
                raise ResolveError(f"{what}: 'keep(it == …)' needs a parameter ('keep(it.name == …)')",
                                   member.location)
            raise NameLookupError(f"{what} has no parameter '{'.'.join(keep.path)}'", member.location)
        if keep.path[0] in bound or keep.path[0] in keeps:
            raise ArgumentError(f"{what}: parameter '{keep.path[0]}' is given twice", member.location)
        keeps[keep.path[0]] = keep
    return _WithMembers(keeps, nested, modifiers, untils, conditions)


def _argument(name: str, fdecl: FieldDecl, bound: dict[str, syntax.Argument], members: _WithMembers,
              node: syntax.Invocation, scope: Scope, what: str) -> TypedExpr:
    """The value of parameter ``name`` of the action call: the argument given, else its keep, else its
    default (an empty list for a list), with the keeps on its members merged in."""
    if name in bound:
        arg = bound[name]
        value = coerce(resolve_expression(arg.value, scope, fdecl.type), fdecl.type, arg.location,
                       f"{what}, argument '{name}'", lenient_string=True)
    elif name in members.keeps:
        keep = members.keeps[name]
        value = coerce(resolve_expression(keep.value, scope, fdecl.type), fdecl.type, keep.location,
                       f"{what}, parameter '{name}'", lenient_string=True, unit_required=True)
    elif fdecl.default is not None:
        value = coerce(resolve_expression(fdecl.default, Scope(scope.ctx), fdecl.type), fdecl.type,
                       fdecl.location, f"{what}, parameter '{name}'", unit_required=True)
    elif name in members.nested and isinstance(fdecl.type, CompoundType):
        value = instantiate(scope.ctx, fdecl.type, {}, [], scope.ctx.fresh_path(name), node.location)
    elif isinstance(fdecl.type, ListType):
        # a list left out is empty, as the reference passes it (ros_launch(...) without its arguments)
        value = TypedExpr(model.Const([]), fdecl.type, True)
    else:
        raise ArgumentError(f"{what}: missing argument '{name}'", node.location)
    if name in members.nested:        # partial overrides merged into the value given, kept or defaulted
        value = apply_nested_keeps(scope.ctx, value, members.nested[name], name, node.location)
    return value


def _wait(node: syntax.Wait, scope: Scope) -> model.Behavior:
    cond = node.condition
    if isinstance(cond, syntax.Call) and isinstance(cond.callee, syntax.Identifier) \
            and cond.callee.name == "elapsed" and scope.lookup("elapsed") is None:
        bound = bind_arguments(["duration"], cond.arguments, "'elapsed(...)'", cond.location)
        if "duration" not in bound:
            raise ArgumentError("'elapsed(...)' needs a duration", cond.location)
        arg = bound["duration"]
        value = resolve_expression(arg.value, scope)
        is_time = isinstance(value.type, PhysicalType) and value.type.name == "time"
        # A number computed at run time (an external method's result) counts as seconds; a number
        # written in the file needs its unit.
        run_time_number = is_numeric(value.type) and not value.is_const
        if not (is_time or run_time_number or value.type is ANY):
            raise OscTypeError(f"'elapsed(...)' needs a time with its unit (e.g. 3s), got {value.type}",
                               arg.location)
        if value.is_const and not (0 <= cast(float, value.value) < math.inf):
            raise ArgumentError(f"'elapsed(...)' needs a finite, non-negative time, got {value.value} s",
                                arg.location)
        return model.WaitElapsed(node.label or "wait", value.expr, node.location)
    if isinstance(cond, syntax.EventRef):
        key = ".".join(cond.path)
        if key not in scope.events:
            raise NameLookupError(f"unknown event '{key}'", cond.location)
        return model.WaitEvent(node.label or "wait", scope.events[key], node.location)
    value = resolve_expression(cond, scope)
    if value.type is not BOOL:
        raise OscTypeError(f"'wait' needs a condition (bool) or 'elapsed(...)', got {value.type}", cond.location)
    return model.WaitCondition(node.label or "wait", value.expr, node.location)


def _emit(node: syntax.Emit, scope: Scope) -> model.Behavior:
    if node.arguments:
        raise UnsupportedFeatureError("not supported: event arguments", node.location)
    if node.event in ("end", "fail"):
        return model.EmitEvent(node.label or f"emit {node.event}", node.event, node.location)
    if node.event not in scope.events:
        raise NameLookupError(f"unknown event '{node.event}'", node.location)
    return model.EmitEvent(node.label or f"emit {node.event}", scope.events[node.event], node.location)



def _coverage_misplaced(decl: syntax.CoverageDecl) -> ResolveError:
    return ResolveError(f"{decl.kind}() is a member of a scenario (or of a parameter's 'with:' block), not of a "
                        "behaviour's 'with:' block", decl.location)


def apply_until(behavior: model.Behavior, untils: list[syntax.Until], scope: Scope) -> model.Behavior:
    """``until @event``: the behaviour runs until the event is emitted, then succeeds (outside its modifiers)."""
    for until in untils:
        condition = until.condition
        if not isinstance(condition, syntax.EventRef):
            raise UnsupportedFeatureError("not supported: 'until' with a condition; write 'until @event'",
                                          condition.location)
        key = ".".join(condition.path)
        if key not in scope.events:
            raise NameLookupError(f"unknown event '{key}'", condition.location)
        behavior = model.Modified("until", (("event", scope.events[key]),), behavior, until.location)
    return behavior
