"""Resolve calls of external methods (``def f(a: int = 1) -> string is external module.function()``).

A call is checked here -- its arguments against the signature, the defaults with their declared
types -- and becomes a :class:`~coverage_engine.resolve.model.ExternalCall`; the Python function is
imported only when the call is computed at run time (:mod:`~coverage_engine.resolve.evaluate`).
Arguments and defaults are resolved through
:attr:`ResolveContext.resolve_expression <coverage_engine.resolve.scope.ResolveContext>`: the
expression resolver calls this module, so this module does not import it.
"""

from __future__ import annotations

from coverage_engine.errors import ArgumentError, ResolveError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve import model
from coverage_engine.resolve.operations import bind_arguments, coerce
from coverage_engine.resolve.scope import ResolveContext, Scope, TypedExpr
from coverage_engine.resolve.types import ANY, CompoundType


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
            default = coerce(ctx.resolve_expression(p.default, scope, ptype), ptype, p.default.location,
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
            value = coerce(ctx.resolve_expression(arg.value, scope, ptype), ptype, arg.location, f"argument '{name}'")
            values.append((name, value.expr))
        elif default is not None:
            values.append((name, default))
        else:
            raise ArgumentError(f"method '{method.name}': missing argument '{name}'", location)
    rtype = ctx.namespace.lookup_type(decl.return_type) if decl.return_type is not None else ANY
    return TypedExpr(model.ExternalCall(method, tuple(values), location), rtype, False)

