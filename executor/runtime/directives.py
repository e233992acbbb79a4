"""Leaf behaviours for the language's own directives: ``wait``, ``emit`` and ``call``.

Each follows the py_trees life cycle: configuration in ``__init__``, per-activation state in
``initialise``, one non-blocking step in ``update``. They read time from the scenario's clock (wall
or simulation) and values from the scenario's variables through the shared
:class:`~executor.runtime.context.ScenarioContext`. :func:`is_pure` marks the conditions that cannot
change while no action runs, which :mod:`~executor.runtime.quiescence` relies on to skip idle ticks.
"""

from __future__ import annotations

from typing import Any

import py_trees
from py_trees.common import Status

from coverage_engine.resolve.model import Const, Expr, FieldOf, MakeList, MakeStruct, Operation, VariableRef
from executor.runtime.context import ScenarioContext, ScenarioEnd


def is_pure(expr: Expr) -> bool:
    """True when computing ``expr`` depends on variables only (no external method)."""
    if isinstance(expr, (Const, VariableRef)):
        return True
    if isinstance(expr, Operation):
        return all(is_pure(o) for o in expr.operands)
    if isinstance(expr, FieldOf):
        return is_pure(expr.target)
    if isinstance(expr, MakeList):
        return all(is_pure(i) for i in expr.items)
    if isinstance(expr, MakeStruct):
        return all(is_pure(v) for _, v in expr.members)
    return False


class WaitElapsed(py_trees.behaviour.Behaviour):
    """``wait elapsed(d)``: running until ``d`` seconds of scenario time have passed since activation."""

    def __init__(self, name: str, duration: Expr, context: ScenarioContext) -> None:
        super().__init__(name)
        self.duration_expr = duration
        self.context = context
        self.finish = 0.0
        self.duration = 0.0

    def initialise(self) -> None:
        value: Any = self.context.value(self.duration_expr)   # float() says whether it is a duration
        try:
            self.duration = float(value)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"wait elapsed(): {value!r} is not a duration") from exc
        self.finish = self.context.clock.now() + self.duration

    def update(self) -> Status:
        if self.context.clock.now() >= self.finish:
            return Status.SUCCESS
        self.feedback_message = f"{self.finish - self.context.clock.now():.3f}s left of {self.duration}s"
        return Status.RUNNING


class WaitCondition(py_trees.behaviour.Behaviour):
    """``wait <condition>``: running until the condition, computed each tick, is true."""

    def __init__(self, name: str, condition: Expr, context: ScenarioContext) -> None:
        super().__init__(name)
        self.condition = condition
        self.context = context
        #: depends on variables only, so it cannot change while no action runs
        self.pure = is_pure(condition)

    def update(self) -> Status:
        return Status.SUCCESS if self.context.value(self.condition) else Status.RUNNING


class WaitEvent(py_trees.behaviour.Behaviour):
    """``wait @event``: running until the event has been emitted."""

    def __init__(self, name: str, event: str, context: ScenarioContext) -> None:
        super().__init__(name)
        self.event = event
        self.context = context

    def update(self) -> Status:
        return Status.SUCCESS if self.event in self.context.events else Status.RUNNING


class EmitEvent(py_trees.behaviour.Behaviour):
    """``emit event``; ``end`` and ``fail`` end the whole scenario on the spot."""

    def __init__(self, name: str, event: str, context: ScenarioContext) -> None:
        super().__init__(name)
        self.event = event
        self.context = context

    def update(self) -> Status:
        if self.event == "end":
            raise ScenarioEnd(True, behaviour=self)
        if self.event == "fail":
            raise ScenarioEnd(False, "emit fail", behaviour=self)
        self.context.events.add(self.event)
        if self.context.coverage is not None:
            self.context.coverage.on_event(self.event)
        return Status.SUCCESS


class CallMethod(py_trees.behaviour.Behaviour):
    """``call …``: computes the expression (an external method) for its effect."""

    def __init__(self, name: str, call: Expr, context: ScenarioContext) -> None:
        super().__init__(name)
        self.call = call
        self.context = context

    def update(self) -> Status:
        self.context.value(self.call)
        return Status.SUCCESS
