"""Compute model expressions (:data:`coverage_engine.resolve.model.Expr`) against current variable values.

The resolver folds everything it can into :class:`~coverage_engine.resolve.model.Const`; what remains
(variables, external methods) is computed here while a scenario runs. External methods are imported
on first use, so a scenario parses and resolves without importing user code; those of the standard
libraries are provided by the runtime (:func:`provide_module`).
"""

from __future__ import annotations

import importlib
import operator
import sys
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any, cast

from coverage_engine.errors import UserError
from coverage_engine.resolve.model import (
    Const,
    Expr,
    ExternalCall,
    ExternalMethod,
    FieldOf,
    MakeList,
    MakeStruct,
    Operation,
    VariableRef,
)


class EvaluationError(UserError):
    """An expression could not be computed at run time (e.g. an external method raised)."""


_BINARY: dict[str, Callable] = {
    "+": operator.add,
    "-": operator.sub,
    "*": operator.mul,
    "/": operator.truediv,  # int / int is a float, as the resolver types it
    "%": operator.mod,
    "==": operator.eq,
    "!=": operator.ne,
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
    "in": lambda a, b: a in b,
}


def apply_operator(op: str, values: list) -> Any:
    """Apply operator ``op`` to already computed operand values (shared by the resolver's folding)."""
    if op == "neg":
        return -values[0]
    if op == "not":
        return not values[0]
    if op == "and":
        return bool(values[0]) and bool(values[1])
    if op == "or":
        return bool(values[0]) or bool(values[1])
    return _BINARY[op](values[0], values[1])


_function_cache: dict[tuple[str, str], Callable] = {}


def add_import_paths(paths: Iterable[str | Path]) -> None:
    """Make user modules importable from these folders (working directory, scenario directory)."""
    for path in paths:
        text = str(Path(path).resolve())
        if text not in sys.path:
            sys.path.insert(0, text)


def provide_module(module: str, functions: Mapping[str, Callable]) -> None:
    """Serve external methods declared as ``module.<name>`` with ``functions`` instead of importing ``module``.

    The runtime provides the functions the standard libraries declare (``osc.helpers``), so the
    language's own files name no module of the runtime.
    """
    for name, func in functions.items():
        _function_cache[(module, name)] = func


def external_function(method: ExternalMethod) -> Callable:
    """Import the Python function behind an external method, once."""
    key = (method.module, method.function)
    func = _function_cache.get(key)
    if func is None:
        try:
            module = importlib.import_module(method.module)
        except Exception as exc:  # noqa: BLE001 - any import failure is the user's module
            raise EvaluationError(
                f"cannot import module '{method.module}' of external method '{method.name}': {exc}",
                method.location) from exc
        func = getattr(module, method.function, None)
        if not callable(func):
            raise EvaluationError(
                f"module '{method.module}' has no function '{method.function}' (external method '{method.name}')",
                method.location)
        _function_cache[key] = func
    return func


def evaluate(expr: Expr, variables: Mapping[str, object]) -> object:
    """The value of ``expr`` now; ``variables`` maps :attr:`Variable.key` to the current value."""
    if isinstance(expr, Const):
        return expr.value
    if isinstance(expr, VariableRef):
        return variables[expr.variable.key]
    if isinstance(expr, Operation):
        values = [evaluate(o, variables) for o in expr.operands]
        try:
            return apply_operator(expr.op, values)
        except Exception as exc:  # noqa: BLE001
            raise EvaluationError(f"cannot compute '{expr.op}' of {values}: {exc}", expr.location) from exc
    if isinstance(expr, FieldOf):
        return cast(dict, evaluate(expr.target, variables))[expr.name]
    if isinstance(expr, MakeList):
        return [evaluate(i, variables) for i in expr.items]
    if isinstance(expr, MakeStruct):
        return {name: evaluate(v, variables) for name, v in expr.members}
    if isinstance(expr, ExternalCall):
        func = external_function(expr.method)
        kwargs = {name: evaluate(v, variables) for name, v in expr.arguments}
        try:
            return func(**kwargs)
        except Exception as exc:  # noqa: BLE001 - user code
            raise EvaluationError(
                f"external method '{expr.method.name}' ({expr.method.module}.{expr.method.function}) "
                f"failed: {type(exc).__name__}: {exc}", expr.location) from exc
    raise TypeError(f"not an expression: {expr!r}")
