"""Action plugins: argument binding, the registry, run_process and process_log_check."""

from __future__ import annotations

import io
import time

import pytest
from py_trees.common import Status
from runtime_models import LOC, action, ref, var

from coverage_engine.resolve import model as m
from executor.actions import ActionBase, registry
from executor.runtime.builder import BuildError, make_action
from executor.runtime.context import ScenarioContext
from executor.runtime.logger import Logger
from executor.runtime.simulation import WallClock

CALLS: list = []


class InitAndExecute(ActionBase):
    """Takes 'first' in __init__, the rest in execute()."""

    def __init__(self, first):
        super().__init__()
        CALLS.append(("init", first))

    def setup(self, **kwargs):
        CALLS.append(("setup", sorted(k for k in kwargs if k in ("logger", "input_dir", "output_dir"))))

    def execute(self, second, third="default"):
        CALLS.append(("execute", second, third))

    def update(self):
        return Status.SUCCESS


class NeedsMissing(ActionBase):
    def execute(self, absent):
        pass


@pytest.fixture
def plugins(monkeypatch):
    CALLS.clear()
    monkeypatch.setitem(registry.BUILTIN_ACTIONS, "init_and_execute", "test_runtime_actions:InitAndExecute")
    monkeypatch.setitem(registry.BUILTIN_ACTIONS, "needs_missing", "test_runtime_actions:NeedsMissing")


def context(out=None) -> ScenarioContext:
    return ScenarioContext(name="t", clock=WallClock(), logger=Logger(stream=out or io.StringIO()))


def test_init_consumes_named_arguments_execute_gets_current_values(plugins):
    counter = var("n", 1)
    ctx = context()
    ctx.init_variables(m.Scenario("t", "t.osc", (), (counter,), (), None, LOC))
    behaviour = make_action(action("init_and_execute", label="my_label", first=ref(counter),
                                   second=ref(counter)), ctx)
    assert behaviour.name == "my_label"
    assert CALLS == [("init", 1)]
    ctx.variables["n"] = 7
    behaviour.setup(logger=ctx.logger, input_dir=None, output_dir=None)
    behaviour.tick_once()
    assert CALLS[1:] == [("setup", ["input_dir", "logger", "output_dir"]), ("execute", 7, "default")]


def test_missing_execute_argument_is_a_build_error(plugins):
    with pytest.raises(BuildError, match="'absent'"):
        make_action(action("needs_missing"), context())


def test_action_without_implementation_names_group():
    call = action("nowhere_to_be_found")
    with pytest.raises(registry.ActionNotFoundError, match="scenario_execution.actions"):
        registry.check_actions_available([m.Scenario("t", "t.osc", (), (), (), call, LOC)])


def test_builtins_found_without_entry_point_scan(monkeypatch):
    monkeypatch.setattr(registry, "_entry_points", None)
    assert registry.find_plugin(action("log"))[0] == "log"
    assert registry._entry_points is None


def tick_until_done(behaviour, timeout=5.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        behaviour.tick_once()
        if behaviour.status != Status.RUNNING:
            return behaviour.status
        time.sleep(0.01)
    return behaviour.status


def test_run_process_splits_quotes_and_logs_output():
    out = io.StringIO()
    ctx = context(out)
    behaviour = make_action(action("run_process", label="p", command="printf '%s\\n' 'two words'"), ctx)
    behaviour.setup(context=ctx)
    assert tick_until_done(behaviour) == Status.SUCCESS
    for _ in range(100):
        if behaviour.output_complete():
            break
        time.sleep(0.01)
    assert behaviour.output_lines() == ["two words"]
    assert "[p] two words" in out.getvalue()
    assert ctx.processes["p"] == [behaviour]


def test_run_process_exit_code_fails():
    behaviour = make_action(action("run_process", command="false"), context())
    assert tick_until_done(behaviour) == Status.FAILURE


def test_run_process_background_is_stopped_at_shutdown():
    behaviour = make_action(action("run_process", command="sleep 30", wait_for_shutdown=False,
                                   shutdown_signal=m.EnumValue("sigint", 2), shutdown_timeout=2.0), context())
    behaviour.tick_once()
    assert behaviour.status == Status.SUCCESS
    process = behaviour.process
    assert process.poll() is None
    started = time.monotonic()
    behaviour.shutdown()
    assert process.poll() is not None and time.monotonic() - started < 2.0


def test_process_log_check_finds_text():
    ctx = context()
    proc = make_action(action("run_process", label="my_proc", command="echo hello-there"), ctx)
    proc.setup(context=ctx)
    assert tick_until_done(proc) == Status.SUCCESS
    found = make_action(action("process_log_check", process_name="my_proc", values=["nope", "hello"]), ctx)
    found.setup(context=ctx)
    assert tick_until_done(found) == Status.SUCCESS
    missing = make_action(action("process_log_check", process_name="my_proc", values=["nope"]), ctx)
    missing.setup(context=ctx)
    assert tick_until_done(missing) == Status.FAILURE
