"""``log(msg)``: print a message (strings as they are, other values as Python prints them)."""

from __future__ import annotations

from typing import Any

from py_trees.common import Status

from executor.actions.base import ActionBase, ActionError


class Log(ActionBase):
    """Logs ``msg`` once per activation and succeeds."""

    def execute(self, msg: Any = None) -> None:
        if msg is None:
            raise ActionError("log(): no message given")
        self.msg = msg

    def update(self) -> Status:
        self.logger.info(self.msg)
        return Status.SUCCESS
