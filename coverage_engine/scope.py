"""What the resolver knows while it works: typed values, name scopes and the per-file context.

A :class:`TypedExpr` pairs a model expression (folded to :class:`~coverage_engine.model.Const` where
possible) with its type. A :class:`Scope` maps visible names to typed values; it falls back to its
parent and finally to the globals of the :class:`ResolveContext`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from coverage_engine import model, syntax
from coverage_engine.namespace import Namespace
from coverage_engine.types import CompoundType, OscType


@dataclass(frozen=True, slots=True)
class TypedExpr:
    """A resolved value: its model expression and its type. ``is_literal`` marks values written as
    literals (no reference to other names): only parameters with such defaults can be overridden."""

    expr: model.Expr
    type: OscType
    is_literal: bool = False

    @property
    def is_const(self) -> bool:
        return isinstance(self.expr, model.Const)

    @property
    def value(self) -> object:
        assert isinstance(self.expr, model.Const)
        return self.expr.value


@dataclass
class Scope:
    """Names visible at one place: local values, ``it``, then the parent scope, then globals."""

    ctx: ResolveContext
    names: dict[str, TypedExpr] = field(default_factory=dict)
    it: TypedExpr | None = None
    parent: Scope | None = None
    events: dict[str, str] = field(default_factory=dict)

    def lookup(self, name: str) -> TypedExpr | None:
        scope: Scope | None = self
        while scope is not None:
            found = scope.names.get(name)
            if found is not None:
                return found
            scope = scope.parent
        return None

    def child(self, names: dict[str, TypedExpr] | None = None, it: TypedExpr | None = None) -> Scope:
        return Scope(self.ctx, names if names is not None else {}, it, self, dict(self.events))


@dataclass
class ResolveContext:
    """State of one resolution: the namespace, global values computed so far, the variables created
    for the scenario being resolved, and the parameter overrides of the run."""

    namespace: Namespace
    overrides: Mapping[str, object] | None = None
    global_values: dict[str, TypedExpr] = field(default_factory=dict)
    globals_in_progress: list[str] = field(default_factory=list)
    variables: list[model.Variable] = field(default_factory=list)
    methods: dict[int, model.ExternalMethod] = field(default_factory=dict)
    counter: int = 0

    def fresh_path(self, hint: str) -> str:
        """A unique key prefix for variables of an instance that has no name of its own."""
        self.counter += 1
        return f"{hint}#{self.counter}"


@dataclass(frozen=True)
class KeepValue:
    """A ``keep(it.a.b == value)`` reduced to the member path below ``it`` and the value's syntax."""

    path: tuple[str, ...]
    value: syntax.Expression
    scope: Scope
    location: syntax.Location
    is_default: bool = False


def compound_members(ctype: CompoundType) -> list[str]:
    """Names of the parameter members of ``ctype`` in order (inherited first)."""
    return list(ctype.fields)
