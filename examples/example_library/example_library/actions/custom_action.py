"""``custom_action(data, repeat_count)``: logs ``data`` on ``repeat_count`` ticks, then succeeds."""

from __future__ import annotations

import py_trees

from executor.actions import ActionBase


class CustomAction(ActionBase):
    """The tutorial's custom action."""

    def __init__(self, repeat_count: int):
        # configuration: arguments named here are passed once, with their initial values
        super().__init__()
        self.repeat_count = repeat_count
        self.data = ""
        self.done = 0

    def setup(self, **kwargs):
        # resources: logger, input_dir, output_dir (and simulation in step-based mode)
        self.output_dir = kwargs.get("output_dir")

    def execute(self, data: str):
        # activation: the other arguments, with their current values
        self.data = data
        self.done = 0

    def update(self) -> py_trees.common.Status:
        self.done += 1
        self.logger.info(f"custom_action: {self.data} ({self.done}/{self.repeat_count})")
        if self.done < self.repeat_count:
            return py_trees.common.Status.RUNNING
        return py_trees.common.Status.SUCCESS
