"""Whole scenarios built by hand from the model and run by ScenarioRunner on a simulation clock."""

from __future__ import annotations

import io

import pytest
from runtime_models import (
    LOC,
    action,
    emit,
    log,
    modified,
    one_of,
    op,
    parallel,
    ref,
    scenario,
    serial,
    var,
    wait_elapsed,
    wait_event,
    wait_until,
)

from coverage_engine.resolve import model as m
from executor.runtime.context import ScenarioContext
from executor.runtime.logger import Logger
from executor.runtime.simulation import SimulationClock
from executor.runtime.tick_loop import ScenarioRunner


class Steps:
    """A minimal simulation: counts steps (dt 0.1 s)."""

    dt = 0.1

    def __init__(self) -> None:
        self.steps = 0

    def step(self) -> None:
        self.steps += 1


def run(model: m.Scenario, max_steps: int = 10_000):
    out = io.StringIO()
    sim = Steps()
    clock = SimulationClock(sim.dt)
    ctx = ScenarioContext(name=model.name, clock=clock, logger=Logger(stream=out))
    original = sim.step

    def bounded_step():
        original()
        assert sim.steps <= max_steps, "scenario did not end"

    sim.step = bounded_step
    result = ScenarioRunner(model, ctx, simulation=sim, tick_period=sim.dt).run()
    lines = [line.split("] ", 2)[-1] for line in out.getvalue().splitlines()]
    return result, lines, sim.steps, ctx


def test_serial_logs_in_order_and_succeeds():
    result, lines, steps, _ = run(scenario(serial(log("a"), wait_elapsed(1.0), log("b"))))
    assert result.passed
    assert [x for x in lines if x in ("a", "b")] == ["a", "b"]
    assert lines[0] == "Executing scenario 'test'" and lines[-1] == "Scenario 'test' succeeded."
    assert 10 <= steps <= 12


def test_log_prints_values_as_python_does():
    values = [1.5, 3, True, [1, 2], {"x": 1.0}, m.EnumValue("sigint", 2)]
    result, lines, _, _ = run(scenario(serial(*(log(v) for v in values))))
    assert result.passed
    assert lines[1:7] == ["1.5", "3", "True", "[1, 2]", "{'x': 1.0}", "('sigint', 2)"]


def test_emit_end_stops_everything_at_once():
    body = parallel(serial(log("before"), emit("end"), log("never")), serial(wait_elapsed(0.05), log("other")))
    result, lines, steps, _ = run(scenario(body))
    assert result.passed and "never" not in lines and "other" not in lines
    assert steps == 1


def test_emit_fail_fails_with_snapshot():
    result, lines, _, _ = run(scenario(serial(log("x"), emit("fail"), log("never"))))
    assert not result.passed
    assert result.message == "emit fail at test.osc:1:1"
    assert "test" in result.output and "log" in result.output
    assert "never" not in lines


def test_parallel_waits_for_all_and_one_of_for_first():
    result, _, steps, _ = run(scenario(parallel(wait_elapsed(1.0), wait_elapsed(2.0))))
    assert result.passed and 20 <= steps <= 22
    result, _, steps, _ = run(scenario(one_of(wait_elapsed(100.0), wait_elapsed(0.5))))
    assert result.passed and 5 <= steps <= 7


def test_events_and_variables_between_branches():
    counter = var("counter", 0)
    body = parallel(
        serial(wait_event("go"), action("increment", target_variable=ref(counter)),
               wait_until(op("==", ref(counter), m.Const(2))), log("done")),
        serial(wait_elapsed(0.5), emit("go"), action("increment", target_variable=ref(counter))),
    )
    result, lines, _, ctx = run(scenario(body, variables=[counter], events=["go"]))
    assert result.passed and "done" in lines
    assert ctx.variables["counter"] == 2


def test_log_of_variable_prints_current_value():
    counter = var("counter", 5)
    body = serial(action("decrement", target_variable=ref(counter)), log(ref(counter)))
    result, lines, _, _ = run(scenario(body, variables=[counter]))
    assert result.passed and "4" in lines


def test_increment_of_a_plain_value_fails():
    result, _, _, _ = run(scenario(serial(action("increment", target_variable=3))))
    assert not result.passed and "must be a 'var'" in result.message


def test_compare_reads_variables_when_it_runs():
    counter = var("counter", 0)
    ok = serial(action("increment", target_variable=ref(counter)),
                action("compare", left_value=ref(counter), operator="==", right_value=1))
    assert run(scenario(ok, variables=[counter]))[0].passed
    bad = serial(action("compare", left_value=ref(counter), operator=">", right_value=1), log("never"))
    result, lines, _, _ = run(scenario(bad, variables=[counter]))
    assert not result.passed and "never" not in lines


def test_scenario_timeout_on_the_simulation_clock():
    body = modified("timeout", serial(log("TEST"), wait_elapsed(30.0)), duration=2.0)
    result, _, steps, _ = run(scenario(body))
    assert not result.passed and 20 <= steps <= 23


def test_repeat_root_runs_serial_twice():
    body = modified("repeat", serial(log("A"), log("B")), count=2)
    result, lines, _, _ = run(scenario(body))
    assert result.passed and [x for x in lines if x in "AB"] == ["A", "B", "A", "B"]


def test_retry_with_inverter_counts_attempts():
    body = modified("retry", modified("inverter", serial(log("RETRY"), wait_elapsed(0.2))), count=3)
    result, lines, _, _ = run(scenario(body))
    assert not result.passed and lines.count("RETRY") == 3


def test_external_method_error_fails_the_run():
    method = m.ExternalMethod("boom", "json", "loads", (("s", "string", None),), "string", LOC)
    call = m.ExternalCall(method, (("s", m.Const("{not json")),), LOC)
    result, lines, _, _ = run(scenario(serial(log(call), log("never"))))
    assert not result.passed and "external method 'boom'" in result.message and "never" not in lines


def test_wait_elapsed_takes_its_duration_when_it_starts():
    counter = var("d", 0.3, "time")
    body = serial(wait_elapsed(0.1), m.WaitElapsed("w", ref(counter), LOC))
    result, _, steps, _ = run(scenario(body, variables=[counter]))
    assert result.passed and 4 <= steps <= 6


def test_unknown_action_fails_setup():
    result, _, _, _ = run(scenario(serial(action("no_such_action_xyz"))))
    assert not result.passed and result.message.startswith("setup failed")
    assert "scenario_execution.actions" in result.message


@pytest.mark.parametrize("body", [None, serial()])
def test_empty_scenario_succeeds(body):
    assert run(scenario(body))[0].passed


@pytest.mark.parametrize("body", [
    serial(log("a"), wait_elapsed(1.0), log("b")),
    modified("timeout", serial(wait_elapsed(0.5), wait_elapsed(5.0)), duration=2.0),
    parallel(serial(wait_elapsed(0.3), emit("go"), wait_elapsed(0.7)), serial(wait_event("go"), log("got"))),
    one_of(wait_elapsed(3.0), modified("timeout", wait_elapsed(9.0), duration=1.25)),
    modified("repeat", serial(wait_elapsed(0.2), log("r")), count=3),
    modified("retry", modified("inverter", wait_elapsed(0.35)), count=2),
    modified("success_is_running", wait_elapsed(0.2)),
])
def test_skipping_idle_ticks_changes_nothing(body):
    outcomes = []
    for skip in (True, False):
        sim = Steps()
        out = io.StringIO()
        ctx = ScenarioContext(name="t", clock=SimulationClock(sim.dt), logger=Logger(stream=out))
        original = sim.step

        def bounded(original=original, sim=sim):
            original()
            if sim.steps > 200:
                raise KeyboardInterrupt

        sim.step = bounded
        runner = ScenarioRunner(scenario(body), ctx, simulation=sim, tick_period=sim.dt, skip_idle_ticks=skip)
        try:
            result = runner.run()
            summary = (result.passed, result.message)
        except Exception as exc:  # noqa: BLE001 - RunAborted for the endless one
            summary = ("aborted", type(exc).__name__)
        lines = [line.split("] ", 2)[-1] for line in out.getvalue().splitlines()]
        outcomes.append((summary, sim.steps, lines, runner.ticks))
    assert outcomes[0][:3] == outcomes[1][:3]
    assert outcomes[0][3] < outcomes[1][3]  # the same run, in fewer ticks
