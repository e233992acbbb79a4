"""Modifiers and composites, ticked by hand with scripted leaves: one row per tick."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.common import Status

from executor.runtime.context import ScenarioContext
from executor.runtime.logger import Logger
from executor.runtime.modifiers import ModifierError, build_modifier
from executor.runtime.simulation import SimulationClock

S, F, R = Status.SUCCESS, Status.FAILURE, Status.RUNNING


class Scripted(py_trees.behaviour.Behaviour):
    """Returns the scripted statuses one per tick (the last one repeats); counts activations."""

    def __init__(self, *statuses: Status) -> None:
        super().__init__("scripted")
        self.script = list(statuses)
        self.ticks = 0
        self.activations = 0

    def initialise(self) -> None:
        self.activations += 1

    def update(self) -> Status:
        status = self.script[min(self.ticks, len(self.script) - 1)]
        self.ticks += 1
        return status


def context() -> ScenarioContext:
    return ScenarioContext(name="t", clock=SimulationClock(1.0), logger=Logger(debug=False))


def tick_table(root: py_trees.behaviour.Behaviour, ticks: int, clock: SimulationClock | None = None) -> list:
    rows = []
    for _ in range(ticks):
        if clock is not None:
            clock.advance()
        root.tick_once()
        rows.append(root.status)
    return rows


@pytest.mark.parametrize("modifier, child, expected", [
    ("inverter", [S], [F]),
    ("inverter", [F], [S]),
    ("inverter", [R, S], [R, F]),
    ("failure_is_running", [F], [R]),
    ("failure_is_success", [F], [S]),
    ("running_is_failure", [R], [F]),
    ("running_is_success", [R], [S]),
    ("success_is_failure", [S], [F]),
    ("success_is_running", [S], [R]),
])
def test_status_converters(modifier, child, expected):
    root = build_modifier(modifier, {}, Scripted(*child), context())
    assert tick_table(root, len(expected)) == expected


def test_repeat_counts_successes_then_succeeds():
    leaf = Scripted(S)
    root = build_modifier("repeat", {"count": 3}, leaf, context())
    assert tick_table(root, 3) == [R, R, S]
    assert leaf.activations == 3


def test_repeat_forever_and_failure_stops():
    leaf = Scripted(S, S, S, F)
    root = build_modifier("repeat", {"count": -1}, leaf, context())
    assert tick_table(root, 4) == [R, R, R, F]


def test_retry_until_count_failures():
    leaf = Scripted(F)
    root = build_modifier("retry", {"count": 3}, leaf, context())
    assert tick_table(root, 3) == [R, R, F]
    assert leaf.activations == 3


def test_retry_stops_at_first_success():
    root = build_modifier("retry", {"count": 3}, Scripted(F, S), context())
    assert tick_table(root, 2) == [R, S]


def test_timeout_uses_the_scenario_clock():
    ctx = context()
    leaf = Scripted(R)
    root = build_modifier("timeout", {"duration": 2.0}, leaf, ctx)
    # activated at t=1: running while t <= 3, fails at t=4 and stops the child
    assert tick_table(root, 4, ctx.clock) == [R, R, R, F]
    assert leaf.status == Status.INVALID


def test_timeout_passes_child_result():
    ctx = context()
    root = build_modifier("timeout", {"duration": 5.0}, Scripted(R, S), ctx)
    assert tick_table(root, 2, ctx.clock) == [R, S]


def test_nesting_retry_outside_inverter():
    ctx = context()
    leaf = Scripted(S)
    root = build_modifier("retry", {"count": 3}, build_modifier("inverter", {}, leaf, ctx), ctx)
    assert tick_table(root, 3) == [R, R, F]
    assert leaf.activations == 3


def test_unknown_modifier_and_bad_arguments():
    with pytest.raises(ModifierError, match="no implementation"):
        build_modifier("not_supported", {}, Scripted(S), context())
    with pytest.raises(ModifierError, match="integer"):
        build_modifier("repeat", {"count": "x"}, Scripted(S), context())
    with pytest.raises(ModifierError, match="required"):
        build_modifier("retry", {}, Scripted(S), context())
