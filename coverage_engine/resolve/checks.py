"""Checks of declarations that no scenario uses: a wrong default is an error even in an unused struct.

Only the declarations of the file being run are checked (libraries are trusted, and checking them
on every run would cost start-up time).
"""

from __future__ import annotations

from coverage_engine.errors import ResolveError
from coverage_engine.parse import syntax
from coverage_engine.resolve.external_methods import external_method
from coverage_engine.resolve.instances import field_value, instantiate
from coverage_engine.resolve.scope import ResolveContext, Scope
from coverage_engine.resolve.types import CompoundType

#: Parameter names the runtime gives every action itself; a declared action may not use them.
RESERVED_ACTION_PARAMETERS = ("name", "associated_actor")


def check_declarations(ctx: ResolveContext, unit: syntax.CompilationUnit) -> None:
    """Resolve every member default, keep and method signature declared in ``unit``."""
    for decl in unit.declarations:
        if not isinstance(decl, syntax.TypeDecl):
            continue
        ctype = ctx.namespace.types.get(decl.name.dotted)
        if not isinstance(ctype, CompoundType) or ctype.declaration is not decl:
            continue
        saved = list(ctx.variables)
        try:
            _check(ctx, ctype)
        finally:
            ctx.variables = saved


def _check(ctx: ResolveContext, ctype: CompoundType) -> None:
    for method in ctype.methods.values():
        external_method(ctx, method, ctype)
    if ctype.kind in ("struct", "actor"):
        instantiate(ctx, ctype, {}, [], ctx.fresh_path(ctype.name), ctype.declaration.location)
        return
    if ctype.kind == "action":
        for name, fdecl in ctype.fields.items():
            if name in RESERVED_ACTION_PARAMETERS:
                raise ResolveError(f"action '{ctype.name}': parameter name '{name}' is reserved", fdecl.location)
    if ctype.kind in ("action", "modifier"):
        scope = Scope(ctx)
        for name, fdecl in ctype.fields.items():
            if fdecl.default is not None:
                field_value(ctx, fdecl.type, fdecl.default, fdecl.with_members, scope, name, fdecl.location,
                            f"parameter '{name}' of {ctype.kind} '{ctype.name}'")
