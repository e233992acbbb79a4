"""Build the py_trees tree of one scenario from the resolved model.

``serial`` → ``Sequence(memory=True)``; ``parallel`` → ``Parallel`` that succeeds when all children
did; ``one_of`` → ``Parallel`` that ends as soon as one child ends; members keep their label as
name. Actions are plugin instances whose arguments are bound here: the ones their ``__init__`` names
are computed now, the rest each time the action starts (see :mod:`executor.actions.base`). Their
life-cycle methods are guarded so that an exception from plugin code names the action and where it
is invoked (:class:`ActionRuntimeError`), the way a failing ``__init__`` does.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

import py_trees
from py_trees.common import ParallelPolicy

from coverage_engine.errors import OscError
from coverage_engine.resolve.evaluate import EvaluationError, evaluate
from coverage_engine.resolve.model import (
    ActionCall,
    Behavior,
    CallMethod,
    Composite,
    EmitEvent,
    Expr,
    Modified,
    Scenario,
    VariableRef,
    WaitCondition,
    WaitElapsed,
    WaitEvent,
)
from executor.actions.base import ActionError, VariableHandle
from executor.actions.registry import load_action_class
from executor.runtime import directives
from executor.runtime.context import ScenarioContext, ScenarioEnd
from executor.runtime.modifiers import ModifierError, build_modifier


class BuildError(OscError):
    """cannot build the behaviour tree"""


class ActionRuntimeError(OscError):
    """an action failed while the scenario ran"""


def build_tree(scenario: Scenario, context: ScenarioContext) -> py_trees.behaviour.Behaviour:
    """The root of the scenario's tree: a sequence named after the scenario holding its body."""
    root = py_trees.composites.Sequence(name=scenario.name, memory=True)
    if scenario.body is not None:
        root.add_child(build_behavior(scenario.body, context))
    return root


def build_behavior(node: Behavior, context: ScenarioContext) -> py_trees.behaviour.Behaviour:
    """One model behaviour (and everything below it) as a py_trees behaviour.

    Each behaviour keeps the location of what it was built from in ``osc_location``, so a failure
    can say where in the scenario it happened.
    """
    behaviour = _build(node, context)
    behaviour.osc_location = getattr(node, "location", None)  # type: ignore[attr-defined]
    behaviour.osc_labelled = bool(getattr(node, "labelled", False))  # type: ignore[attr-defined]
    return behaviour


def _build(node: Behavior, context: ScenarioContext) -> py_trees.behaviour.Behaviour:
    if isinstance(node, Composite):
        composite: py_trees.composites.Composite
        if node.kind == "serial":
            composite = py_trees.composites.Sequence(name=node.name, memory=True)
        elif node.kind == "parallel":
            composite = py_trees.composites.Parallel(name=node.name, policy=ParallelPolicy.SuccessOnAll())
        elif node.kind == "one_of":
            composite = py_trees.composites.Parallel(name=node.name, policy=ParallelPolicy.SuccessOnOne())
        else:
            raise BuildError(f"unknown composition '{node.kind}'", node.location)
        for child in node.children:
            composite.add_child(build_behavior(child, context))
        return composite
    if isinstance(node, ActionCall):
        return make_action(node, context)
    if isinstance(node, Modified):
        decorated = build_behavior(node.child, context)
        try:
            return build_modifier(node.modifier, dict(node.arguments), decorated, context)
        except ModifierError as exc:
            raise BuildError(str(exc), node.location) from exc
    if isinstance(node, WaitElapsed):
        return directives.WaitElapsed(node.name, node.duration, context)
    if isinstance(node, WaitCondition):
        return directives.WaitCondition(node.name, node.condition, context)
    if isinstance(node, WaitEvent):
        return directives.WaitEvent(node.name, node.event, context)
    if isinstance(node, EmitEvent):
        return directives.EmitEvent(node.name, node.event, context)
    if isinstance(node, CallMethod):
        return directives.CallMethod(node.name, node.call, context)
    raise BuildError(f"cannot run {type(node).__name__}", getattr(node, "location", None))


# --------------------------------------------------------------------------------------------------
# Actions


def _parameters(function: Callable[..., object]) -> tuple[Mapping[str, inspect.Parameter], bool]:
    """Named parameters of ``function`` (without self) and whether it takes ``**kwargs``.

    Known per function (a bound method by its function): ``inspect.signature`` is the costly part of
    making an action, and every action of a class has the same signature.
    """
    unbound = getattr(function, "__func__", None)
    return _signature_parameters(unbound, True) if unbound is not None else _signature_parameters(function, False)


@functools.lru_cache(maxsize=1024)
def _signature_parameters(function: Callable[..., object], bound: bool) -> tuple[Mapping[str, inspect.Parameter], bool]:
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return MappingProxyType({}), True
    parameters = list(signature.parameters.values())
    if bound and parameters and parameters[0].kind in (inspect.Parameter.POSITIONAL_ONLY,
                                                       inspect.Parameter.POSITIONAL_OR_KEYWORD):
        parameters = parameters[1:]           # what the bound method's own signature leaves out
    named, var_keyword = {}, False
    for parameter in parameters:
        if parameter.kind is inspect.Parameter.VAR_KEYWORD:
            var_keyword = True
        elif parameter.kind is not inspect.Parameter.VAR_POSITIONAL and parameter.name != "self":
            named[parameter.name] = parameter
    return MappingProxyType(named), var_keyword


def make_action(call: ActionCall, context: ScenarioContext) -> py_trees.behaviour.Behaviour:
    """Instantiate the plugin for ``call`` with its arguments bound; raises :class:`BuildError`."""
    cls = load_action_class(call)
    if not issubclass(cls, py_trees.behaviour.Behaviour):
        raise BuildError(f"plugin for action '{call.action}' ({cls.__name__}) is not a py_trees behaviour "
                         "(derive it from executor.actions.ActionBase)", call.location)
    arguments = dict(call.arguments)
    if call.actor is not None:
        arguments["associated_actor"] = call.actor

    init_parameters, _ = _parameters(cls.__init__)
    init_names = [n for n in init_parameters if n in arguments]
    missing = [n for n, p in init_parameters.items()
               if p.default is inspect.Parameter.empty and n not in arguments]
    if missing:
        raise BuildError(f"action '{call.action}': {cls.__name__}.__init__() needs {_names(missing)}, "
                         "which the invocation does not give", call.location)
    try:
        init_values: dict[str, Any] = {n: context.value(arguments[n]) for n in init_names}
        instance = cls(**init_values)
    except OscError:
        raise
    except Exception as exc:  # noqa: BLE001 - plugin code or an external method
        raise BuildError(f"action '{call.action}': cannot create {cls.__name__}: {type(exc).__name__}: {exc}",
                         call.location) from exc

    rest = {n: e for n, e in arguments.items() if n not in init_values}
    execute = getattr(instance, "execute", None)
    if execute is not None:
        execute_parameters, takes_any = _parameters(execute)
        selected = rest if takes_any else {n: e for n, e in rest.items() if n in execute_parameters}
        missing = [n for n, p in execute_parameters.items()
                   if p.default is inspect.Parameter.empty and n not in selected]
        if missing:
            raise BuildError(f"action '{call.action}': {cls.__name__}.execute() needs {_names(missing)}, "
                             "which the invocation does not give", call.location)
        if hasattr(instance, "_execute_arguments"):
            instance._execute_arguments = _argument_binder(instance, selected, context)
    instance.name = call.name
    instance.logger = context.logger.child(call.name)  # type: ignore[assignment] # same methods as py_trees'
    _guard_life_cycle(instance, call)
    return instance


#: The plugin methods whose exceptions are reported with the action's name and location.
GUARDED_METHODS = ("setup", "initialise", "execute", "update", "terminate", "shutdown")

#: Exceptions that pass unchanged: control flow, and errors that already say where they come from.
_PASS_THROUGH = (ScenarioEnd, OscError, EvaluationError)


def _guard_life_cycle(instance: object, call: ActionCall) -> None:
    """Wrap the instance's life-cycle methods (instance attributes: the class stays untouched)."""
    for phase in GUARDED_METHODS:
        method = getattr(instance, phase, None)
        if method is not None:
            setattr(instance, phase, _guarded(method, phase, call))


def _guarded(method: Callable, phase: str, call: ActionCall) -> Callable:
    def guarded(*args: Any, **kwargs: Any) -> Any:
        try:
            return method(*args, **kwargs)
        except _PASS_THROUGH:
            raise
        except ActionError as exc:  # the action's own message is meant for users
            raise ActionRuntimeError(f"action '{call.action}': {exc}", call.location) from exc
        except Exception as exc:  # noqa: BLE001 - plugin code
            raise ActionRuntimeError(f"action '{call.action}': {phase}() raised {type(exc).__name__}: {exc}",
                                     call.location) from exc

    guarded.__wrapped__ = method  # type: ignore[attr-defined]
    return guarded


def _names(names: list[str]) -> str:
    return ", ".join(f"'{n}'" for n in names)


def _argument_binder(instance: object, selected: dict[str, Expr], context: ScenarioContext) -> Callable[[], dict]:
    """A function computing ``execute``'s keyword arguments from the current variable values."""
    variables = context.variables

    def arguments() -> dict:
        handles = not getattr(instance, "resolve_variable_reference_arguments_in_execute", True)
        values: dict[str, object] = {}
        for name, expr in selected.items():
            if handles and isinstance(expr, VariableRef):
                values[name] = VariableHandle(expr.variable.key, variables)
            else:
                values[name] = evaluate(expr, variables)
        return values

    return arguments
