"""``compare(left_value, operator, right_value)``: succeed if the comparison holds, fail otherwise."""

from __future__ import annotations

import operator as op
from collections.abc import Callable
from typing import Any

from py_trees.common import Status

from executor.actions.base import ActionBase, ActionError

_OPERATORS: dict[str, Callable[[Any, Any], Any]] = {"==": op.eq, "!=": op.ne, "<": op.lt, "<=": op.le, ">": op.gt, ">=": op.ge}


def _current(value: object) -> object:
    get_value = getattr(value, "get_value", None)
    return get_value() if callable(get_value) else value


class Compare(ActionBase):
    """Compares the current values (variables are read at the tick the comparison runs)."""

    def __init__(self) -> None:
        super().__init__(resolve_variable_reference_arguments_in_execute=False)

    def execute(self, left_value: object, operator: str, right_value: object) -> None:
        function = _OPERATORS.get(str(operator))
        if function is None:
            raise ActionError(f"compare(): unknown operator '{operator}' (use one of {', '.join(_OPERATORS)})")
        self.function = function
        self.operator = operator
        self.left_value = left_value
        self.right_value = right_value

    def update(self) -> Status:
        left, right = _current(self.left_value), _current(self.right_value)
        try:
            holds = self.function(left, right)
        except TypeError as exc:
            raise ActionError(f"compare(): cannot compare {left!r} {self.operator} {right!r}: {exc}") from exc
        self.feedback_message = f"{left!r} {self.operator} {right!r} is {bool(holds)}"
        return Status.SUCCESS if holds else Status.FAILURE
