"""``keep(...)`` constraints: a value to apply, or a condition to check.

``keep(it.a.b == value)`` (and ``keep(default …)``) fixes a member: :class:`KeepValue`. Any other
boolean keep (``keep(it >= 2m)``, ``keep(goal_x > start_x)``, ``keep(not (w == snow and s > 80kph))``)
is a condition on values fixed elsewhere: :class:`KeepCheck`, checked once the members it names have
their values (:func:`check_keep`). A ``keep(… in [...])`` is what ``scenario_variation`` expands into
concrete scenarios first; when a scenario runs it is an error.
"""

from __future__ import annotations

from dataclasses import dataclass

from coverage_engine.errors import ResolveError, UnsupportedFeatureError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve.scope import KeepValue, ResolveExpression, Scope, TypedExpr
from coverage_engine.resolve.types import BOOL, STRING, CompoundType

#: Operators whose keep is a condition (``==`` on a member path is a value, ``in`` a variation).
_CONDITIONS = frozenset({"!=", "<", "<=", ">", ">=", "and", "or", "=>"})


class ConstraintViolation(ResolveError):
    """a keep condition does not hold for the values the scenario has"""


@dataclass(frozen=True)
class KeepCheck:
    """A ``keep(<condition>)`` to check once the names it uses have their values."""

    expression: syntax.Expression
    scope: Scope
    location: Location


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
    """Reduce ``keep(it.path == value)`` to a :class:`KeepValue`; anything else is an error here.

    For places that also take conditions, see :func:`classify_keep`.
    """
    found = classify_keep(keep, scope)
    if isinstance(found, KeepCheck):
        raise UnsupportedFeatureError("not supported: a keep condition here (only 'keep(it.member == value)')",
                                      keep.location)
    return found


def classify_keep(keep: syntax.KeepConstraint, scope: Scope) -> KeepValue | KeepCheck:
    """A value to apply (``keep(it.path == value)``) or a condition to check (any other boolean keep)."""
    expr = keep.expression
    if isinstance(expr, syntax.BinaryOp):
        path = it_path(expr.left)
        if path is not None and expr.op == "==":
            return KeepValue(path, expr.right, scope, keep.location, keep.is_default)
        if path is not None and expr.op == "in":
            raise UnsupportedFeatureError(
                "not supported: 'keep(... in [...])' when running a scenario; expand it into concrete "
                "scenarios with scenario_variation", keep.location)
        if expr.op in _CONDITIONS and not keep.is_default:
            return KeepCheck(expr, scope, keep.location)
    if isinstance(expr, syntax.UnaryOp) and expr.op == "not" and not keep.is_default:
        return KeepCheck(expr, scope, keep.location)
    raise UnsupportedFeatureError("not supported: this keep constraint (a condition, or "
                                  "'keep(it.member == value)')", keep.location)


def split_type_keeps(ctype: CompoundType, scope: Scope) -> tuple[list[KeepValue], list[KeepCheck]]:
    """The keeps among a type's members: values to apply, and (for a scenario) conditions to check.

    A condition among the members of an actor or struct is refused: it would need a solver to choose
    each instance's values (the reference tool refuses every keep but ``==`` there too).
    """
    values, checks = split_with_keeps(tuple(ctype.keeps), scope)
    if checks and ctype.kind != "scenario":
        raise UnsupportedFeatureError(
            f"not supported: a keep condition among the members of {ctype.kind} '{ctype.name}' (it would "
            "need a solver to choose each instance's values); fix a value with 'keep(member == value)', "
            "or put the condition in the scenario or in a 'with:' block", checks[0].location)
    return values, checks


def split_with_keeps(with_members: tuple, scope: Scope) -> tuple[list[KeepValue], list[KeepCheck]]:
    """A declaration's ``with:`` keeps: values to apply, and conditions (``keep(it >= 2m)``) to check."""
    values: list[KeepValue] = []
    checks: list[KeepCheck] = []
    for member in with_members:
        if isinstance(member, syntax.KeepConstraint):
            found = classify_keep(member, scope)
            if isinstance(found, KeepCheck):
                checks.append(found)
            else:
                values.append(found)
    return values, checks


def check_keep(check: KeepCheck, names: dict[str, TypedExpr], it: TypedExpr | None,
               resolve_expression: ResolveExpression) -> None:
    """Check ``check`` with ``names`` (the members) and ``it`` in view; raise when it does not hold.

    The condition must be decidable from values known when the scenario is resolved (parameters,
    constants); one that depends on a variable's runtime value is an error. Resolution in "collect"
    mode (:attr:`ResolveContext.constraints`) records the outcome instead of raising on a violation.
    """
    ctx = check.scope.ctx
    if ctx.constraints == "skip":
        return
    scope = check.scope.child(names, it)
    _refuse_string_order(check.expression, scope, resolve_expression)
    value = resolve_expression(check.expression, scope, BOOL)
    if value.type is not BOOL:
        raise ResolveError(f"a keep condition must be a bool, not {value.type}", check.location)
    if not value.is_const:
        raise UnsupportedFeatureError("not supported: a keep condition on a value known only while the "
                                      "scenario runs", check.location)
    holds = bool(value.value)
    if ctx.constraints == "collect":
        ctx.constraint_results.append((check.location, holds))
        return
    if not holds:
        raise ConstraintViolation(f"constraint does not hold: keep({keep_text(check)})", check.location)


def _refuse_string_order(expr: syntax.Expression, scope: Scope, resolve: ResolveExpression) -> None:
    """A keep condition orders numbers and physical quantities only: ``keep(it.z <= "x")`` is refused.

    Ordering strings is legal in an expression, but in a constraint it is almost always a mistyped
    ``==`` (and the reference tool refuses every keep but ``==``), so it is said rather than checked.
    """
    if isinstance(expr, syntax.UnaryOp):
        _refuse_string_order(expr.operand, scope, resolve)
    elif isinstance(expr, syntax.BinaryOp):
        if expr.op in ("<", "<=", ">", ">="):
            if resolve(expr.left, scope, None).type is STRING:
                raise ResolveError(f"a keep condition cannot order strings with '{expr.op}' (it compares numbers "
                                   "and physical quantities); to fix a value write 'keep(it.member == value)'",
                                   expr.location)
        elif expr.op in ("and", "or", "=>"):
            _refuse_string_order(expr.left, scope, resolve)
            _refuse_string_order(expr.right, scope, resolve)


def keep_text(check: KeepCheck) -> str:
    """The condition as written (blanks collapsed), or a placeholder when the source is not at hand."""
    loc = check.expression.location
    text = check.scope.ctx.texts.get(loc.file)
    if text is None or not loc.end_pos:
        return "…"
    return " ".join(text[loc.start_pos:loc.end_pos].split())
