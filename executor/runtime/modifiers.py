"""The ``osc.helpers`` modifiers as py_trees decorators.

``repeat(count)``: a success starts the child again until ``count`` successes (``-1``: forever); a
failure fails at once. ``retry(count)``: a failure starts the child again, failing on the
``count``-th failure. ``timeout(duration)``: fails (and stops the child) once ``duration`` seconds
of scenario time have passed. ``inverter`` swaps success and failure. The six
``<status>_is_<status>`` converters map one status of the child to another. Several modifiers nest
as the model says (:class:`coverage_engine.resolve.model.Modified`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import py_trees
from py_trees import decorators
from py_trees.common import Status

from executor.actions.registry import BUILTIN_MODIFIERS
from executor.runtime.context import ScenarioContext


class ModifierError(Exception):
    """A modifier the runtime does not implement, or bad arguments for one."""


class ClockTimeout(decorators.Decorator):
    """Fails the child once ``duration`` seconds of scenario time passed since activation."""

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, duration: float,
                 context: ScenarioContext) -> None:
        super().__init__(name=name, child=child)
        self.duration = float(duration)
        self.context = context
        self.finish = 0.0

    def initialise(self) -> None:
        self.finish = self.context.clock.now() + self.duration

    def update(self) -> Status:
        if self.context.clock.now() > self.finish:
            self.feedback_message = f"timed out after {self.duration}s"
            self.decorated.stop(Status.INVALID)
            return Status.FAILURE
        return self.decorated.status


class UntilEvent(decorators.Decorator):
    """``until @event``: runs the child until the event has been emitted, then stops it and succeeds; a child
    that ends first ends the decorator with its own status."""

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, event: str,
                 context: ScenarioContext) -> None:
        super().__init__(name=name, child=child)
        self.event = event
        self.context = context

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        if self.event in self.context.events:       # checked before the child runs again
            if self.decorated.status == Status.RUNNING:
                self.decorated.stop(Status.INVALID)
            self.feedback_message = f"until @{self.event}: the event came"
            self.stop(Status.SUCCESS)
            yield self
            return
        yield from super().tick()

    def update(self) -> Status:
        return self.decorated.status


_CONVERTERS: dict[str, Callable[..., decorators.Decorator]] = {
    "inverter": decorators.Inverter,
    "failure_is_running": decorators.FailureIsRunning,
    "failure_is_success": decorators.FailureIsSuccess,
    "running_is_failure": decorators.RunningIsFailure,
    "running_is_success": decorators.RunningIsSuccess,
    "success_is_failure": decorators.SuccessIsFailure,
    "success_is_running": decorators.SuccessIsRunning,
}

MODIFIERS = ("timeout", "repeat", "retry", *_CONVERTERS)
assert set(MODIFIERS) == set(BUILTIN_MODIFIERS), "keep executor.actions.registry.BUILTIN_MODIFIERS in step"


def _int_argument(modifier: str, arguments: dict, name: str, default: int | None) -> int:
    value = arguments.get(name, default)
    if value is None:
        raise ModifierError(f"{modifier}(): '{name}' is required")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or int(value) != value:
        raise ModifierError(f"{modifier}(): '{name}' must be an integer, got {value!r}")
    return int(value)


def build_modifier(modifier: str, arguments: dict, child: py_trees.behaviour.Behaviour,
                   context: ScenarioContext) -> py_trees.behaviour.Behaviour:
    """The decorator for one modifier application around ``child``."""
    if modifier in _CONVERTERS:
        return _CONVERTERS[modifier](name=modifier, child=child)
    if modifier == "repeat":
        return decorators.Repeat(name="repeat", child=child,
                                 num_success=_int_argument(modifier, arguments, "count", -1))
    if modifier == "retry":
        return decorators.Retry(name="retry", child=child,
                                num_failures=_int_argument(modifier, arguments, "count", None))
    if modifier == "timeout":
        duration = arguments.get("duration")
        if isinstance(duration, bool) or not isinstance(duration, (int, float)):
            raise ModifierError(f"timeout(): 'duration' must be a time, got {duration!r}")
        return ClockTimeout(name="timeout", child=child, duration=duration, context=context)
    if modifier == "until":
        return UntilEvent(name="until", child=child, event=str(arguments.get("event")), context=context)
    raise ModifierError(f"modifier '{modifier}' has no implementation (known: {', '.join(MODIFIERS)})")
