"""``keep(...)`` constraints reduced to what the resolver applies: a member path below ``it`` and a value.

Only ``keep(it.a.b == value)`` (and ``keep(default …)``) is applied when a scenario is resolved; a
``keep(… in [...])`` is what ``scenario_variation`` expands into concrete scenarios first.
"""

from __future__ import annotations

from coverage_engine.errors import UnsupportedFeatureError
from coverage_engine.parse import syntax
from coverage_engine.resolve.scope import KeepValue, Scope


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
