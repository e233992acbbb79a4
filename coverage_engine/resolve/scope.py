"""What the resolver knows while it works: typed values, name scopes and the per-file context.

A :class:`TypedExpr` pairs a model expression (folded to :class:`~coverage_engine.resolve.model.Const` where
possible) with its type. A :class:`Scope` maps visible names to typed values; it falls back to its
parent and finally to the globals of the :class:`ResolveContext`.
"""

from __future__ import annotations

from collections.abc import Callable

from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.records import Record, record
from coverage_engine.resolve import model
from coverage_engine.resolve.namespace import Namespace
from coverage_engine.resolve.types import OscType


@record
class TypedExpr(Record):
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


class Scope:
    """Names visible at one place: local values, ``it``, then the parent scope, then globals."""

    __slots__ = ("ctx", "names", "it", "parent", "events")

    def __init__(self, ctx: ResolveContext, names: dict[str, TypedExpr] | None = None, it: TypedExpr | None = None,
                 parent: Scope | None = None, events: dict[str, str] | None = None) -> None:
        self.ctx = ctx
        self.names = names if names is not None else {}
        self.it = it
        self.parent = parent
        self.events = events if events is not None else {}

    def lookup(self, name: str) -> TypedExpr | None:
        scope: Scope | None = self
        while scope is not None:
            found = scope.names.get(name)
            if found is not None:
                return found
            scope = scope.parent
        return None

    def child(self, names: dict[str, TypedExpr] | None = None, it: TypedExpr | None = None) -> Scope:
        return Scope(self.ctx, names if names is not None else {}, it, self, self.events)  # events are read-only


#: Resolves one expression in a scope (``expected`` guides ``!member`` and list literals):
#: :func:`coverage_engine.resolve.expressions.resolve_expression`.
ResolveExpression = Callable[[syntax.Expression, Scope, "OscType | None"], TypedExpr]


class ResolveContext:
    """State of one resolution: the namespace, global values computed so far and the variables
    created for the scenario being resolved.

    It also carries the expression resolver, ``resolve_expression``: building an instance, calling an
    external method and checking a keep each resolve expressions, and the expression resolver calls
    each of them, so they receive it here instead of importing it (which would close an import circle).
    """

    def __init__(self, namespace: Namespace, resolve_expression: ResolveExpression) -> None:
        self.namespace = namespace
        self.resolve_expression = resolve_expression
        self.global_values: dict[str, TypedExpr] = {}
        self.globals_in_progress: list[str] = []
        self.variables: list[model.Variable] = []
        self.methods: dict[int, model.ExternalMethod] = {}
        self.counter = 0
        #: Types whose instance is being built right now, outermost first (to catch 'struct s: a: s').
        self.building: list[str] = []
        #: Source text of each file, for quoting an expression as written (coverage items' ``ignore:``).
        self.texts: dict[str, str] = {}
        #: Keep conditions: "check" (a violated one is an error), "skip" them, or "collect" each outcome
        #: in :attr:`constraint_results` (``scenario_variation`` finds the combinations they exclude).
        self.constraints = "check"
        self.constraint_results: list[tuple[Location, bool]] = []

    def fresh_path(self, hint: str) -> str:
        """A unique key prefix for variables of an instance that has no name of its own."""
        self.counter += 1
        return f"{hint}#{self.counter}"


@record
class KeepValue(Record):
    """A ``keep(it.a.b == value)`` reduced to the member path below ``it`` and the value's syntax."""

    path: tuple[str, ...]
    value: syntax.Expression
    scope: Scope
    location: Location
    is_default: bool = False
