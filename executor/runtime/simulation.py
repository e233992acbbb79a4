"""Clocks and the step-based simulation interface.

Without a simulation, scenarios run on the wall clock and the tick loop sleeps between ticks. With
``--simulation module:Class`` the simulation owns time: the loop calls :meth:`SimulationInterface.step`
once per tick, a :class:`SimulationClock` advances by ``dt`` per step, and nothing sleeps. ``wait
elapsed`` and ``timeout`` read whichever clock the scenario was given.

Lifecycle of a simulation across one scenario file::

    setup(**kwargs)                      # once
    for each scenario:  reset(**params)  # scenario parameters injected by argument name
                        step() per tick
    shutdown()                           # once

This module imports nothing heavy so the command line can load a simulation before deciding to run.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import math
import numbers
import sys
import time
from abc import ABC, abstractmethod
from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

from coverage_engine.errors import UserError


class SimulationError(UserError):
    """A simulation could not be loaded, or does not fit the scenario (e.g. missing reset arguments)."""


class SimulationStepError(SimulationError):
    """The simulation's ``step()`` raised while a scenario ran (the scenario fails)."""


def simulation_dt(simulation: Any) -> float:
    """The simulation's ``dt`` as seconds; :class:`SimulationError` unless it is a positive, finite number."""
    name = type(simulation).__name__
    try:
        dt = simulation.dt
    except Exception as exc:  # noqa: BLE001 - user code (a property)
        raise SimulationError(f"simulation {name}: reading dt raised {type(exc).__name__}: {exc}") from exc
    if isinstance(dt, bool) or not isinstance(dt, numbers.Real) or not math.isfinite(dt) or dt <= 0:
        raise SimulationError(f"simulation {name}: dt must be a positive, finite number of seconds, got {dt!r}")
    return float(dt)


class Clock:
    """A time source in seconds; ``now()`` is all behaviours use."""

    def now(self) -> float:
        raise NotImplementedError


class WallClock(Clock):
    """Monotonic host time, zero at construction (a fresh one per scenario)."""

    __slots__ = ("_start",)

    def __init__(self) -> None:
        self._start = time.monotonic()

    def now(self) -> float:
        return time.monotonic() - self._start


class SimulationClock(Clock):
    """Time as ``steps × dt``: advanced once per simulation step, reset before each scenario.

    Counting steps (instead of adding ``dt`` up) keeps long runs free of accumulated rounding error.
    """

    __slots__ = ("dt", "steps", "_time")
    dt: float
    steps: int
    _time: float

    def __init__(self, dt: float) -> None:
        if isinstance(dt, bool) or not isinstance(dt, numbers.Real) or not math.isfinite(dt) or dt <= 0:
            raise SimulationError(f"simulation dt must be a positive, finite number of seconds, got {dt!r}")
        self.dt = float(dt)
        self.steps = 0
        self._time = 0.0

    def now(self) -> float:
        return self._time

    def advance(self) -> None:
        self.steps += 1
        self._time = self.steps * self.dt

    def reset(self) -> None:
        self.steps = 0
        self._time = 0.0


#: A user's simulation object as the runtime sees it: duck-typed (``dt`` and ``step`` required; ``setup``,
#: ``reset`` and ``shutdown`` optional; ``reset`` taking the scenario parameters it wants as its own
#: arguments), so it has no static type beyond :class:`SimulationInterface`'s description.
UserSimulation = Any


class SimulationInterface(ABC):
    """Base class for a step-based simulation (or system under test) driven by the tick loop.

    Implement ``dt`` and ``step()``; override ``setup``, ``reset`` and ``shutdown`` as needed.
    ``reset`` declares the scenario parameters it wants as ordinary arguments::

        def reset(self, speed, label="none"):   # 'speed' must exist in the scenario
            ...

    Struct parameters arrive as nested dicts, values in SI base units, overrides already applied.
    Actions get the simulation object as ``simulation`` in their ``setup(**kwargs)``.
    """

    @property
    @abstractmethod
    def dt(self) -> float:
        """Seconds of simulated time per :meth:`step`."""

    def setup(self, **kwargs: Any) -> None:  # noqa: B027 - optional hook
        """Acquire resources once per file; gets ``logger``, ``output_dir``, ``tick_period``."""

    def reset(self, **kwargs: Any) -> None:  # noqa: B027 - optional hook
        """Bring the simulation to its start state for the next scenario."""

    @abstractmethod
    def step(self) -> None:
        """Advance by ``dt``; called once per tick before the tree is ticked. Must not block."""

    def shutdown(self) -> None:  # noqa: B027 - optional hook
        """Release resources once, after the last scenario."""


# --------------------------------------------------------------------------------------------------
# Loading ``--simulation``


def load_simulation(spec: str) -> object:
    """Instantiate the simulation named by ``module.path:Class`` or ``path/to/file.py[:Class]``.

    Raises :class:`SimulationError` with a one-line reason for anything that does not work.
    """
    if ":" in spec:
        target, class_name = spec.rsplit(":", 1)
    else:
        target, class_name = spec, None
    if not target:
        raise SimulationError(f"--simulation '{spec}': expected 'module.path:Class' or 'file.py:Class'")
    if target.endswith(".py") or "/" in target:
        module = _import_file(target)
    else:
        if class_name is None:
            raise SimulationError(f"--simulation '{spec}': expected 'module.path:Class' or 'file.py:Class'")
        if "" not in sys.path and str(Path.cwd()) not in sys.path:
            sys.path.insert(0, str(Path.cwd()))
        try:
            module = importlib.import_module(target)
        except Exception as exc:  # noqa: BLE001 - any import failure is the user's module
            raise SimulationError(f"--simulation: cannot import module '{target}': {exc}") from exc
    cls = _pick_class(module, target, class_name)
    try:
        simulation = cls()
    except Exception as exc:  # noqa: BLE001 - user code
        raise SimulationError(f"--simulation: cannot create {cls.__name__}(): {type(exc).__name__}: {exc}") from exc
    for member in ("dt", "step"):
        if not hasattr(simulation, member):
            raise SimulationError(f"--simulation: {cls.__name__} has no '{member}' (see SimulationInterface)")
    return simulation


def _import_file(target: str) -> ModuleType:
    path = Path(target).resolve()
    if not path.is_file():
        raise SimulationError(f"--simulation: file not found: {target}")
    name = path.stem
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise SimulationError(f"--simulation: cannot load {target}")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault(name, module)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # noqa: BLE001 - user code
        raise SimulationError(f"--simulation: cannot load {target}: {type(exc).__name__}: {exc}") from exc
    return module


def _pick_class(module: ModuleType, target: str, class_name: str | None) -> type:
    if class_name:
        cls = getattr(module, class_name, None)
        if not isinstance(cls, type):
            raise SimulationError(f"--simulation: no class '{class_name}' in '{target}'")
        return cls
    candidates = [obj for _, obj in inspect.getmembers(module, inspect.isclass)
                  if obj.__module__ == module.__name__]
    if len(candidates) != 1:
        found = ", ".join(c.__name__ for c in candidates) or "none"
        raise SimulationError(f"--simulation: name the class as '{target}:Class' (classes found: {found})")
    return candidates[0]


# --------------------------------------------------------------------------------------------------
# Injecting scenario parameters into ``reset``


def _reset_parameters(simulation: UserSimulation) -> list[inspect.Parameter]:
    try:
        signature = inspect.signature(simulation.reset)
    except (TypeError, ValueError):
        return []
    return [p for p in signature.parameters.values()
            if p.kind not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)]


def reset_arguments(simulation: UserSimulation, parameters: Mapping[str, object],
                    scenario_name: str = "") -> dict[str, object]:
    """The keyword arguments for ``simulation.reset``: scenario parameters matching its argument names.

    Raises :class:`SimulationError` naming every required argument the scenario does not declare.
    """
    wanted = _reset_parameters(simulation)
    missing = [p.name for p in wanted if p.default is inspect.Parameter.empty and p.name not in parameters]
    if missing:
        names = ", ".join(f"'{n}'" for n in missing)
        where = f"scenario '{scenario_name}'" if scenario_name else "the scenario"
        raise SimulationError(
            f"{type(simulation).__name__}.reset() requires parameter(s) {names}, which {where} does not declare")
    return {p.name: parameters[p.name] for p in wanted if p.name in parameters}
