"""Small constructors of :mod:`coverage_engine.resolve.model` objects for runtime tests (no parser needed)."""

from __future__ import annotations

from coverage_engine.location import Location
from coverage_engine.resolve import model as m

LOC = Location("test.osc", 1, 1)


def const(value):
    return m.Const(value)


def var(key: str, initial=0, type_name: str = "int") -> m.Variable:
    return m.Variable(key, type_name, m.Const(initial), LOC)


def ref(variable: m.Variable) -> m.VariableRef:
    return m.VariableRef(variable)


def op(operator: str, *operands) -> m.Operation:
    return m.Operation(operator, tuple(operands), LOC)


def serial(*children, name: str = "serial") -> m.Composite:
    return m.Composite("serial", name, tuple(children), LOC)


def parallel(*children, name: str = "parallel") -> m.Composite:
    return m.Composite("parallel", name, tuple(children), LOC)


def one_of(*children, name: str = "one_of") -> m.Composite:
    return m.Composite("one_of", name, tuple(children), LOC)


def action(name: str, label: str | None = None, **arguments) -> m.ActionCall:
    args = tuple((k, v if isinstance(v, (m.Const, m.VariableRef, m.Operation, m.ExternalCall, m.MakeList,
                                         m.MakeStruct, m.FieldOf)) else m.Const(v))
                 for k, v in arguments.items())
    return m.ActionCall(name, (name,), label or name, args, None, LOC)


def log(msg) -> m.ActionCall:
    return action("log", msg=msg)


def wait_elapsed(seconds: float) -> m.WaitElapsed:
    return m.WaitElapsed("wait", m.Const(seconds), LOC)


def wait_until(condition) -> m.WaitCondition:
    return m.WaitCondition("wait", condition, LOC)


def wait_event(event: str) -> m.WaitEvent:
    return m.WaitEvent(f"wait @{event}", event, LOC)


def emit(event: str) -> m.EmitEvent:
    return m.EmitEvent(f"emit {event}", event, LOC)


def modified(modifier: str, child, **arguments) -> m.Modified:
    return m.Modified(modifier, tuple(arguments.items()), child, LOC)


def scenario(body, name: str = "test", variables=(), parameters=(), events=()) -> m.Scenario:
    return m.Scenario(name, "test.osc", tuple(parameters), tuple(variables), tuple(events), body, LOC)


def parameter(name: str, value, type_name: str = "float") -> m.Parameter:
    return m.Parameter(name, type_name, value, LOC)
