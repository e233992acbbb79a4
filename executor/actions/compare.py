"""``compare(left_value, operator, right_value)``: succeed if the comparison holds, fail otherwise.

Each evaluation of an ordering of two numbers also tells the run how far it was from flipping (its
*margin*, :func:`check_margin`); the run keeps the closest one (the runtime context's ``note_check_margin``)
as the ``check.margin`` property of its report, which ``scenario_variation --strategy falsify
--objective margin`` minimises.
"""

from __future__ import annotations

import operator as op
from collections.abc import Callable
from typing import Any

from py_trees.common import Status

from executor.actions.base import ActionBase, ActionError

_OPERATORS: dict[str, Callable[[Any, Any], Any]] = {"==": op.eq, "!=": op.ne, "<": op.lt, "<=": op.le, ">": op.gt, ">=": op.ge}


def check_margin(operator: str, left: object, right: object) -> float | None:
    """How far ``left operator right`` is from flipping, relative to the larger of the two magnitudes: positive
    while it holds, negative when it fails (``132 <= 80``: -0.39). None for anything but an ordering (``<``,
    ``<=``, ``>``, ``>=``) of two numbers: an equality has no distance to flip, a string no magnitude."""
    numbers = (int, float)
    if operator not in ("<", "<=", ">", ">=") or not isinstance(left, numbers) or not isinstance(right, numbers) \
            or isinstance(left, bool) or isinstance(right, bool):
        return None
    difference = float(right) - float(left) if operator in ("<", "<=") else float(left) - float(right)
    scale = max(abs(float(left)), abs(float(right)))
    return difference / scale if scale > 0 else difference


def _current(value: object) -> object:
    get_value = getattr(value, "get_value", None)
    return get_value() if callable(get_value) else value


class Compare(ActionBase):
    """Compares the current values (variables are read at the tick the comparison runs)."""

    def __init__(self) -> None:
        super().__init__(resolve_variable_reference_arguments_in_execute=False)
        #: The run's ``note_check_margin`` (the runtime's context hands it over in ``setup``), if any.
        self.note_margin: Callable[[float], None] | None = None

    def setup(self, **kwargs: Any) -> None:
        note = getattr(kwargs.get("context"), "note_check_margin", None)
        self.note_margin = note if callable(note) else None

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
        margin = check_margin(str(self.operator), left, right)
        if margin is not None and self.note_margin is not None:
            self.note_margin(margin)
        return Status.SUCCESS if holds else Status.FAILURE
