"""``increment(target_variable)`` and ``decrement(target_variable)`` of a ``var``."""

from __future__ import annotations

from typing import Any

from py_trees.common import Status

from executor.actions.base import ActionBase, ActionError


class _Step(ActionBase):
    step = 0

    def __init__(self) -> None:
        super().__init__(resolve_variable_reference_arguments_in_execute=False)
        self.target: Any = None              # a var handle (get_value, set_value, key)

    def execute(self, target_variable: object) -> None:
        if not (hasattr(target_variable, "get_value") and hasattr(target_variable, "set_value")):
            raise ActionError(f"{self.name}(): 'target_variable' must be a 'var', "
                              f"got the value {target_variable!r}")
        self.target = target_variable

    def update(self) -> Status:
        value = self.target.get_value()
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ActionError(f"{self.name}(): variable '{self.target.key}' holds {value!r}, not a number")
        self.target.set_value(value + self.step)
        return Status.SUCCESS


class Increment(_Step):
    """Adds one to the variable."""

    step = 1


class Decrement(_Step):
    """Subtracts one from the variable."""

    step = -1
