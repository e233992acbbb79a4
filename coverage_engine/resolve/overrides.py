"""Apply one YAML document of ``--scenario-parameter-file`` to a scenario's parameters.

A document maps scenario names to ``{parameter: value}``. Values are plain YAML in SI base units
(``3.5`` for a length is metres), structs are mappings merged over the parameter's current value,
enums are member names, lists replace the whole list (struct elements merged over a default-built
element). Only parameters whose default is written as a literal may be overridden.
"""

from __future__ import annotations

from collections.abc import Mapping

from coverage_engine.errors import ParameterFileError
from coverage_engine.parse import syntax
from coverage_engine.resolve import model
from coverage_engine.resolve.instances import FieldInfo, OverrideHook, instantiate
from coverage_engine.resolve.scope import ResolveContext, TypedExpr
from coverage_engine.resolve.types import CompoundType, ConversionError, ListType, OscType, convert

#: The key of a parameter document's scenario mapping that places that run's results (``_output_dir:
#: fast_run``): read by the runner, never a parameter of the scenario.
OUTPUT_DIR_KEY = "_output_dir"


def scenario_overrides(document: dict | None) -> dict | None:
    """``document`` without the runner's own keys (:data:`OUTPUT_DIR_KEY`): what the resolver applies."""
    if document is None or not any(isinstance(v, dict) and OUTPUT_DIR_KEY in v for v in document.values()):
        return document
    return {name: ({k: v for k, v in values.items() if k != OUTPUT_DIR_KEY} if isinstance(values, dict) else values)
            for name, values in document.items()}


def check_document(document: Mapping | None, scenario_names: list[str]) -> dict[str, Mapping]:
    """The document's per-scenario mappings; errors for anything that is not ``{scenario: {param: value}}``."""
    if document is None:
        return {}
    if not isinstance(document, Mapping):
        raise ParameterFileError("a parameter document must map scenario names to parameters, "
                                 f"got {type(document).__name__}")
    result: dict[str, Mapping] = {}
    for name, values in document.items():
        if name not in scenario_names:
            known = ", ".join(scenario_names) or "none"
            raise ParameterFileError(f"parameter file names unknown scenario '{name}' (scenarios: {known})")
        if values is None:
            values = {}
        if not isinstance(values, Mapping):
            raise ParameterFileError(f"parameters of scenario '{name}' must be a mapping, "
                                     f"got {type(values).__name__}")
        result[str(name)] = values
    return result


def is_literal_default(expr: syntax.Expression | None, ctx: ResolveContext) -> bool:
    """True when a default is written with literals only (constructors of literals count)."""
    if expr is None:
        return True
    if isinstance(expr, (syntax.Literal, syntax.PhysicalLiteral, syntax.EnumValueRef)):
        return True
    if isinstance(expr, syntax.UnaryOp):
        return is_literal_default(expr.operand, ctx)
    if isinstance(expr, syntax.BinaryOp):
        return is_literal_default(expr.left, ctx) and is_literal_default(expr.right, ctx)
    if isinstance(expr, syntax.ListExpr):
        return all(is_literal_default(i, ctx) for i in expr.items)
    if isinstance(expr, syntax.Identifier):
        return isinstance(ctx.namespace.types.get(expr.name), CompoundType)
    if isinstance(expr, syntax.Call) and isinstance(expr.callee, syntax.Identifier):
        return isinstance(ctx.namespace.types.get(expr.callee.name), CompoundType) and all(
            is_literal_default(a.value, ctx) for a in expr.arguments)
    return False


def not_overridable_reason(info: FieldInfo, ctx: ResolveContext) -> str | None:
    """Why a member cannot be set from a parameter file, or None when it can."""
    if not info.is_field:
        return "it is a variable ('var'), not a parameter"
    if _contains_actor(info.type):
        return f"its type '{info.type}' is an actor"
    if not is_literal_default(info.default, ctx):
        return "its default refers to other names"
    return None


def _contains_actor(t: OscType) -> bool:
    if isinstance(t, ListType):
        return _contains_actor(t.element)
    return isinstance(t, CompoundType) and t.kind == "actor"


def override_hook(ctx: ResolveContext, scenario: str, values: Mapping) -> OverrideHook:
    """The hook :func:`~coverage_engine.resolve.instances.instantiate` calls for each member of ``scenario``."""
    unused = set(values)

    def hook(name: str, current: TypedExpr | None, info: FieldInfo) -> TypedExpr | None:
        if name not in values:
            return None
        unused.discard(name)
        where = f"{scenario}.{name}"
        reason = not_overridable_reason(info, ctx)
        if reason is not None:
            raise ParameterFileError(f"parameter '{where}' cannot be overridden: {reason}")
        base = current.value if current is not None and current.is_const else None
        value = from_yaml(ctx, values[name], info.type, base, where)
        return TypedExpr(model.Const(value), info.type, True)

    hook.unused = unused  # type: ignore[attr-defined]
    return hook


def from_yaml(ctx: ResolveContext, raw: object, target: OscType, base: object, where: str) -> object:
    """Convert a YAML value to ``target``; struct mappings are merged over ``base``."""
    if isinstance(target, CompoundType):
        if not isinstance(raw, Mapping):
            raise ParameterFileError(f"parameter '{where}': expected a mapping for {target.name}, "
                                     f"got {_yaml_kind(raw)}")
        merged = dict(base) if isinstance(base, dict) else dict(_default_instance(ctx, target))
        for key, value in raw.items():
            fdecl = target.fields.get(key)
            if fdecl is None:
                known = ", ".join(target.fields) or "none"
                raise ParameterFileError(f"parameter '{where}': '{target.name}' has no member '{key}' "
                                         f"(members: {known})")
            merged[key] = from_yaml(ctx, value, fdecl.type, merged.get(key), f"{where}.{key}")
        return merged
    if isinstance(target, ListType):
        if not isinstance(raw, list):
            raise ParameterFileError(f"parameter '{where}': expected a list ({target.name}), got {_yaml_kind(raw)}")
        return [from_yaml(ctx, item, target.element, None, f"{where}[{i}]") for i, item in enumerate(raw)]
    try:
        return convert(raw, target, f"parameter '{where}'")
    except ConversionError as exc:
        raise ParameterFileError(str(exc)) from exc


def _default_instance(ctx: ResolveContext, ctype: CompoundType) -> dict:
    value = instantiate(ctx, ctype, {}, [], ctx.fresh_path(ctype.name), ctype.declaration.location)
    members = value.value if value.is_const else None
    return members if isinstance(members, dict) else {}


def _yaml_kind(raw: object) -> str:
    if raw is None:
        return "nothing"
    if isinstance(raw, Mapping):
        return "a mapping"
    if isinstance(raw, list):
        return "a list"
    return f"{type(raw).__name__} {raw!r}"
