"""``process_log_check(process_name, values, from_start)``: look for text in a run_process's output.

Succeeds as soon as a line of the output of the ``run_process`` labelled ``process_name`` contains one
of ``values``; fails once that process has ended and none was found.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from py_trees.common import Status

from executor.actions.base import ActionBase, ActionError

if TYPE_CHECKING:
    from executor.actions.run_process import RunProcess


class ProcessLogCheck(ActionBase):
    """Watches the captured output of a labelled run_process."""

    def setup(self, **kwargs: Any) -> None:
        self.context = kwargs.get("context")

    def execute(self, process_name: str, values: list, from_start: bool = True) -> None:
        self.process_name = process_name
        self.values = [str(v) for v in (values or [])]
        self.from_start = from_start
        self.process: RunProcess | None = None
        self.start_index = 0

    def _find_process(self) -> RunProcess:
        candidates = (self.context.processes.get(self.process_name, []) if self.context else [])
        if not candidates:
            raise ActionError(f"process_log_check(): no run_process labelled '{self.process_name}'")
        if len(candidates) > 1:
            raise ActionError(f"process_log_check(): label '{self.process_name}' names several run_process actions")
        return candidates[0]

    def update(self) -> Status:
        process = self.process
        if process is None:
            process = self.process = self._find_process()
            if not self.from_start:
                self.start_index = len(process.output_lines())
        complete = process.output_complete()
        for line in process.output_lines()[self.start_index:]:
            for value in self.values:
                if value in line:
                    self.feedback_message = f"found '{value}' in '{line}'"
                    return Status.SUCCESS
        if complete:
            self.feedback_message = f"none of {self.values} in the output of '{self.process_name}'"
            return Status.FAILURE
        return Status.RUNNING
