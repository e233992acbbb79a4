"""Find the Python class behind an action: our built-ins first, then entry points.

Actions are plugins in the entry-point group ``scenario_execution.actions`` (name → class). Our own
``osc.helpers`` actions are registered there too, but they are looked up here directly, so a run that
only uses built-ins never pays for an entry-point scan. Nothing here imports py_trees: the command
line checks that every invoked action has an implementation during ``-n`` as well.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable, Iterator
from typing import TYPE_CHECKING

from coverage_engine.errors import OscError
from coverage_engine.resolve.model import ActionCall, Behavior, Composite, Modified, Scenario

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

ENTRY_POINT_GROUP = "scenario_execution.actions"

#: Our built-in actions (also registered as entry points in pyproject.toml).
BUILTIN_ACTIONS: dict[str, str] = {
    "log": "executor.actions.log:Log",
    "run_process": "executor.actions.run_process:RunProcess",
    "compare": "executor.actions.compare:Compare",
    "increment": "executor.actions.variables:Increment",
    "decrement": "executor.actions.variables:Decrement",
    "process_log_check": "executor.actions.process_log_check:ProcessLogCheck",
}


#: Modifiers the runtime implements (executor.runtime.modifiers).
BUILTIN_MODIFIERS = ("timeout", "repeat", "retry", "inverter", "failure_is_running", "failure_is_success",
                     "running_is_failure", "running_is_success", "success_is_failure", "success_is_running")


class ActionNotFoundError(OscError):
    """no implementation for action"""


class ModifierNotFoundError(OscError):
    """no implementation for modifier"""


class ActionLoadError(OscError):
    """cannot load the implementation of an action"""


_entry_points: dict[str, EntryPoint] | None = None


def _plugin_entry_points() -> dict[str, EntryPoint]:
    """Entry points of the action group by name (scanned once per process)."""
    global _entry_points
    if _entry_points is None:
        from importlib.metadata import entry_points

        found: dict[str, EntryPoint] = {}
        for ep in entry_points(group=ENTRY_POINT_GROUP):
            found.setdefault(ep.name, ep)
        _entry_points = found
    return _entry_points


def _load_target(target: str) -> type:
    module_name, _, attr = target.partition(":")
    module = importlib.import_module(module_name)
    return getattr(module, attr)


def find_plugin(call: ActionCall) -> tuple[str, str | EntryPoint] | None:
    """``(plugin name, loader)`` of the first available implementation of ``call``, else None.

    The loader is either a built-in ``module:Class`` string or an entry point; nothing is imported.
    """
    for name in call.plugin_names or (call.action,):
        if name in BUILTIN_ACTIONS:
            return name, BUILTIN_ACTIONS[name]
    for name in call.plugin_names or (call.action,):
        ep = _plugin_entry_points().get(name)
        if ep is not None:
            return name, ep
    return None


def _not_found(call: ActionCall) -> ActionNotFoundError:
    tried = ", ".join(f"'{n}'" for n in (call.plugin_names or (call.action,)))
    return ActionNotFoundError(
        f"action '{call.action}' has no implementation: no plugin named {tried} in entry-point group "
        f"'{ENTRY_POINT_GROUP}' (install the package that provides it)", call.location)


def load_action_class(call: ActionCall) -> type:
    """Import the class implementing ``call``; raises :class:`ActionNotFoundError`/:class:`ActionLoadError`."""
    found = find_plugin(call)
    if found is None:
        raise _not_found(call)
    name, loader = found
    try:
        cls = _load_target(loader) if isinstance(loader, str) else loader.load()
    except Exception as exc:  # noqa: BLE001 - a broken plugin package
        raise ActionLoadError(
            f"cannot load plugin '{name}' for action '{call.action}': {type(exc).__name__}: {exc}",
            call.location) from exc
    if not isinstance(cls, type):
        raise ActionLoadError(f"plugin '{name}' for action '{call.action}' is not a class", call.location)
    return cls


def iter_action_calls(behavior: Behavior | None) -> Iterator[ActionCall]:
    """Every :class:`ActionCall` in a behaviour tree of the model, in document order."""
    if behavior is None:
        return
    if isinstance(behavior, ActionCall):
        yield behavior
    elif isinstance(behavior, Composite):
        for child in behavior.children:
            yield from iter_action_calls(child)
    elif isinstance(behavior, Modified):
        yield from iter_action_calls(behavior.child)


def iter_modifiers(behavior: Behavior | None) -> Iterator[Modified]:
    """Every modifier application in a behaviour tree of the model."""
    if isinstance(behavior, Modified):
        yield behavior
        yield from iter_modifiers(behavior.child)
    elif isinstance(behavior, Composite):
        for child in behavior.children:
            yield from iter_modifiers(child)


#: Modifiers that are keywords of the language rather than declared in a library (``until @event``).
LANGUAGE_MODIFIERS = ("until",)


def check_actions_available(scenarios: Iterable[Scenario]) -> None:
    """Raise for the first invoked action or applied modifier without an implementation."""
    for scenario in scenarios:
        for call in iter_action_calls(scenario.body):
            if find_plugin(call) is None:
                raise _not_found(call)
        for applied in iter_modifiers(scenario.body):
            if applied.modifier not in BUILTIN_MODIFIERS and applied.modifier not in LANGUAGE_MODIFIERS:
                raise ModifierNotFoundError(
                    f"modifier '{applied.modifier}' has no implementation (available: "
                    f"{', '.join(BUILTIN_MODIFIERS)})", applied.location)
