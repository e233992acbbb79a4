"""The resolver: a parsed file (with its imports) in, a :class:`~coverage_engine.resolve.model.ScenarioFile` out.

Passes, in order: collect imported files, register and fill declarations, compute globals, then per
scenario build its parameters (overrides applied), variables and events, and resolve its ``do`` body.
Every problem is an :class:`~coverage_engine.errors.OscError` with a location; the source line is
attached here so the message can show a caret.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from coverage_engine.errors import OscError, ParameterFileError, ResolveError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve import model
from coverage_engine.resolve.checks import check_declarations
from coverage_engine.resolve.coverage_items import resolve_coverage
from coverage_engine.resolve.do_body import apply_modifiers, resolve_behavior
from coverage_engine.resolve.expressions import resolve_expression
from coverage_engine.resolve.imports import collect_units
from coverage_engine.resolve.instances import FieldInfo, global_value, instantiate
from coverage_engine.resolve.namespace import Namespace, build_namespace
from coverage_engine.resolve.overrides import check_document, not_overridable_reason, override_hook
from coverage_engine.resolve.scope import ResolveContext, Scope, TypedExpr
from coverage_engine.resolve.types import CompoundType, FieldDecl


def resolve(unit: syntax.CompilationUnit, base_dir: Path | str | None = None,
            overrides: Mapping | None = None, *, constraints: str = "check",
            collected: list[tuple[Location, bool]] | None = None) -> model.ScenarioFile:
    """Resolve ``unit``; ``base_dir`` is where relative imports and user modules are found.

    ``constraints`` says what to do with keep conditions (``keep(x > y)``): "check" them (a violated
    one is a :class:`~coverage_engine.resolve.keeps.ConstraintViolation`), "skip" them, or "collect"
    each one's location and outcome into ``collected``.
    """
    base = Path(base_dir) if base_dir is not None else Path(unit.file).parent
    texts = {unit.file: unit.text}
    try:
        units, namespace = _prepared(unit, base)
        texts.update({u.file: u.text for u in units})
        return _resolve(unit, units, base, overrides, namespace, constraints, collected)
    except OscError as exc:
        _attach_source_line(exc, texts)
        raise
    except RecursionError:
        raise ResolveError("the file is nested too deeply to resolve (an expression or structure of "
                           "thousands of levels)", Location(unit.file, 1, 1)) from None


def _attach_source_line(exc: OscError, texts: dict[str, str]) -> None:
    loc = exc.location
    if exc.source_line is None and loc is not None and loc.file in texts:
        lines = texts[loc.file].splitlines()
        if 1 <= loc.line <= len(lines):
            exc.source_line = lines[loc.line - 1]


#: The imports and namespace of the last unit resolved (a strong reference keeps its id valid): a
#: parameter file of 100,000 documents resolves one file 100,000 times with different overrides, and the
#: declarations do not depend on the overrides (resolution reads the namespace, never changes it).
_last_prepared: tuple[syntax.CompilationUnit, Path, list[syntax.CompilationUnit], Namespace] | None = None


def _prepared(unit: syntax.CompilationUnit, base: Path) -> tuple[list[syntax.CompilationUnit], Namespace]:
    global _last_prepared
    if _last_prepared is not None and _last_prepared[0] is unit and _last_prepared[1] == base:
        return _last_prepared[2], _last_prepared[3]
    units = collect_units(unit, base)
    namespace = build_namespace(units, unit)
    _last_prepared = (unit, base, units, namespace)
    return units, namespace


def _resolve(unit: syntax.CompilationUnit, units: list[syntax.CompilationUnit], base: Path,
             overrides: Mapping | None, namespace: Namespace, constraints: str = "check",
             collected: list[tuple[Location, bool]] | None = None) -> model.ScenarioFile:
    ctx = ResolveContext(namespace, resolve_expression)
    ctx.constraints = constraints
    if collected is not None:
        ctx.constraint_results = collected
    ctx.texts = {u.file: u.text for u in units}
    ctx.texts[unit.file] = unit.text
    for name in namespace.globals:
        global_value(ctx, name, namespace.globals[name].location)
    check_declarations(ctx, unit)
    if not namespace.scenarios:
        raise ResolveError("the file declares no scenario", Location(unit.file, 1, 1))
    _check_unique_scenarios(namespace.scenarios)
    per_scenario = check_document(overrides, [s.name for s in namespace.scenarios])
    scenarios = tuple(_scenario(ctx, s, per_scenario.get(s.name)) for s in namespace.scenarios)
    return model.ScenarioFile(unit.file, scenarios, (str(base),))


def _check_unique_scenarios(scenarios: list[CompoundType]) -> None:
    seen: set[str] = set()
    for s in scenarios:
        if s.name in seen:
            raise ResolveError(f"scenario '{s.name}' is declared twice", s.declaration.name.location)
        seen.add(s.name)


def _scenario(ctx: ResolveContext, stype: CompoundType, values: Mapping | None) -> model.Scenario:
    ctx.variables = []
    names: dict[str, TypedExpr] = {}
    hook = override_hook(ctx, stype.name, values) if values is not None else None
    location = stype.declaration.location
    instantiate(ctx, stype, {}, [], "", location, scope_names=names, override=hook)
    if hook is not None and hook.unused:  # type: ignore[attr-defined]
        unknown = sorted(hook.unused)  # type: ignore[attr-defined]
        known = ", ".join(stype.fields) or "none"
        raise ParameterFileError(f"scenario '{stype.name}' has no parameter '{unknown[0]}' (parameters: {known})")
    events = {name: name for name in stype.events}
    for pname, value in names.items():
        if isinstance(value.type, CompoundType):
            for ancestor in value.type.ancestry():
                for ename in ancestor.events:
                    events.setdefault(f"{pname}.{ename}", f"{pname}.{ename}")
    scope = Scope(ctx, names, events=events)
    body = resolve_behavior(stype.body.behavior, scope) if stype.body is not None else None
    if stype.modifiers:
        if body is None:
            raise ResolveError(f"scenario '{stype.name}' has modifiers but no 'do' body", location)
        body = apply_modifiers(body, stype.modifiers, scope)
    coverage = resolve_coverage(stype, scope) if stype.coverage else ()
    parameters = tuple(
        model.Parameter(name, fdecl.type.name, names[name].value if names[name].is_const else None,
                        fdecl.location, not_overridable_reason(_info(fdecl), ctx) is None)
        for name, fdecl in stype.fields.items())
    return model.Scenario(stype.name, stype.declaration.location.file, parameters, tuple(ctx.variables),
                          tuple(events.values()), body, location, coverage)


def _info(fdecl: FieldDecl) -> FieldInfo:
    return FieldInfo(fdecl.name, fdecl.type, fdecl.default, True, fdecl.location)
