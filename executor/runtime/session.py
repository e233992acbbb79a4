"""Run the planned scenarios of one file in order: clocks, simulation life cycle, signals.

A session owns what spans scenarios: the simulation (``setup`` once, ``reset`` before each scenario
with its parameters, ``shutdown`` once), the SIGINT/SIGTERM handlers (the running scenario is
recorded as failed with "aborted", its processes are ended, nothing else runs and the scenarios that
never started are recorded as skipped), and the list of results. A failing scenario never stops the
following ones. ``on_result`` is called with all results so far each time a scenario finishes (the
command rewrites ``test.xml`` there).
"""

from __future__ import annotations

import os
import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import NoReturn

from coverage_engine.results.scenario_result import CHECK_MARGIN_PROPERTY, ScenarioResult
from executor.runtime import external_methods
from executor.runtime.context import Aborted, ScenarioContext
from executor.runtime.logger import Logger
from executor.runtime.planned_runs import PlannedRun, RunOrigin
from executor.runtime.simulation import (
    Clock,
    SimulationClock,
    SimulationError,
    UserSimulation,
    WallClock,
    reset_arguments,
    simulation_dt,
)

#: The message of a scenario that an abort kept from starting.
NOT_STARTED = "not run: the run was aborted before this scenario started"


class SessionOptions:
    """How to run: tick period (wall clock), simulation, observers (live view), directories."""

    def __init__(self, tick_period: float = 0.1, simulation: object | None = None, input_dir: str | None = None,
                 output_root: str | None = None, observer_factory: Callable[[str], list] | None = None,
                 debug: bool = False,
                 on_result: Callable[[list[ScenarioResult]], object] | None = None,
                 origin: RunOrigin | None = None, scenario_file: str | None = None, bt_log: bool = False,
                 tick_log: bool = False) -> None:
        self.tick_period = tick_period
        self.simulation = simulation
        self.input_dir = input_dir
        self.output_root = output_root
        self.observer_factory = observer_factory
        self.debug = debug
        self.on_result = on_result
        self.origin = origin                 # the file run, for each run's coverage.json
        self.scenario_file = scenario_file   # named in behaviors.jsonl
        self.bt_log = bt_log                 # --bt-log: behaviors.jsonl in each run's folder
        self.tick_log = tick_log             # --tick-log: tick_timing.csv and action_timing.csv there


class SessionOutcome:
    """All recorded results; ``aborted`` is the signal number when a signal ended the session."""

    def __init__(self) -> None:
        self.results: list[ScenarioResult] = []
        self.aborted = 0

    @property
    def passed(self) -> bool:
        return not self.aborted and bool(self.results) and all(r.passed for r in self.results)


@contextmanager
def abort_on_signals() -> Iterator[None]:
    """Turn SIGINT/SIGTERM into :class:`Aborted` in the main thread while scenarios run."""

    def handler(signum: int, _frame: FrameType | None) -> NoReturn:
        raise Aborted(signum)

    previous = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        try:
            previous[signum] = signal.signal(signum, handler)
        except ValueError:  # not the main thread (e.g. embedded use): keep the defaults
            pass
    try:
        yield
    finally:
        for signum, old in previous.items():
            signal.signal(signum, old)


def run_session(runs: list[PlannedRun], options: SessionOptions, logger: Logger) -> SessionOutcome:
    """Run every planned scenario and return the results (never raises for a scenario's failure)."""
    from executor.runtime.tick_loop import RunAborted

    outcome = SessionOutcome()
    results = outcome.results
    simulation = options.simulation
    external_methods.provide()
    with abort_on_signals():
        try:
            sim_clock = None
            if simulation is not None:
                started = _set_up_simulation(simulation, options, logger)
                if isinstance(started, str):
                    results.extend(ScenarioResult(r.name, False, started, output_dir=r.output_dir) for r in runs)
                    return outcome
                sim_clock = started
            for run in runs:
                try:
                    result = _run_one(run, options, logger, sim_clock)
                except RunAborted as aborted:
                    results.append(aborted.result)
                    outcome.aborted = aborted.signum
                    break
                results.append(result)
                if options.on_result is not None:
                    options.on_result(results)
        except Aborted as exc:  # between scenarios (or while a report was written)
            outcome.aborted = exc.signum
        finally:
            if simulation is not None and sim_clock is not None:
                _shut_down(simulation, logger)
    if outcome.aborted:
        recorded = {result.name for result in results}
        results.extend(ScenarioResult(r.name, False, NOT_STARTED, output_dir=r.output_dir, skipped=True)
                       for r in runs if r.name not in recorded)
    return outcome


def _set_up_simulation(simulation: UserSimulation, options: SessionOptions, logger: Logger) -> SimulationClock | str:
    """The simulation's clock once its optional ``setup`` ran, or the message of why it could not start."""
    try:
        sim_clock = SimulationClock(simulation_dt(simulation))
        setup = getattr(simulation, "setup", None)  # optional, like reset and shutdown
        if setup is not None:
            setup(logger=logger, output_dir=options.output_root, tick_period=sim_clock.dt)
    except Exception as exc:  # noqa: BLE001 - user code
        message = str(exc) if isinstance(exc, SimulationError) else \
            f"simulation setup failed: {type(exc).__name__}: {exc}"
        logger.error(message)
        return message
    return sim_clock


def _shut_down(simulation: UserSimulation, logger: Logger) -> None:
    """The simulation's optional ``shutdown``; a failure is logged, never raised."""
    try:
        shutdown = getattr(simulation, "shutdown", None)
        if shutdown is not None:
            shutdown()
    except Exception as exc:  # noqa: BLE001 - user code
        logger.error(f"simulation shutdown failed: {type(exc).__name__}: {exc}")


def _run_one(run: PlannedRun, options: SessionOptions, logger: Logger,
             sim_clock: SimulationClock | None) -> ScenarioResult:
    """One scenario: its folder, the simulation's reset, the run, its check margin and coverage.

    A run that cannot start (no folder, a failed reset) is a failed result; the others still run.
    Raises the tick loop's ``RunAborted`` when a signal ends the run.
    """
    from executor.runtime.tick_loop import ScenarioRunner

    simulation = options.simulation
    if run.output_dir:
        try:
            os.makedirs(run.output_dir, exist_ok=True)
        except (OSError, ValueError) as exc:   # this run cannot run; the others still do
            reason = getattr(exc, "strerror", None) or str(exc)
            message = f"cannot create the output directory {run.output_dir!r}: {reason}"
            logger.error(f"Scenario '{run.name}' not run: {message}")
            return ScenarioResult(run.name, False, message, output_dir=None, error=True)
    external_methods.set_directories(options.input_dir, run.output_dir or options.output_root)
    if simulation is not None and sim_clock is not None:
        failure = _reset_simulation(simulation, run)
        if failure is not None:
            logger.error(f"Scenario '{run.name}' failed: {failure.message}")
            return failure
        sim_clock.reset()
    clock: Clock = sim_clock if sim_clock is not None else WallClock()
    context = ScenarioContext(
        name=run.name, clock=clock,
        logger=logger, input_dir=options.input_dir, output_dir=run.output_dir or options.output_root,
        simulation=simulation, origin=options.origin)
    observers = options.observer_factory(run.name) if options.observer_factory else []
    period = sim_clock.dt if sim_clock is not None else options.tick_period
    runner = ScenarioRunner(run.scenario, context, name=run.name, tick_period=period,
                            simulation=simulation, observers=observers,
                            recorders=_recorders(options, context, run.name, period, logger))
    result = runner.run()
    if context.check_margin is not None:
        result.properties[CHECK_MARGIN_PROPERTY] = repr(context.check_margin)
    if context.coverage is not None:
        _write_coverage(context, result, logger)
    return result


def _recorders(options: SessionOptions, context: ScenarioContext, name: str, period: float,
               logger: Logger) -> list:
    """The ``--bt-log``/``--tick-log`` recorders of one run, announced in the log (none unless asked for)."""
    if not (options.bt_log or options.tick_log) or not context.output_dir:
        return []
    from executor.runtime.recording import ACTION_TIMING, BEHAVIOUR_LOG, TICK_TIMING, recorders

    folder = context.output_dir
    try:
        found = recorders(folder, context.clock, name, options.scenario_file, period, options.bt_log,
                          options.tick_log)
    except OSError as exc:       # e.g. a link planted under the name: the run goes on without its records
        logger.error(f"Scenario '{name}': cannot record into {folder}: {exc.strerror or exc}")
        return []
    if options.bt_log:
        logger.info(f"Recording behaviour tree status to {os.path.join(folder, BEHAVIOUR_LOG)}")
    if options.tick_log:
        logger.info(f"Recording tick timing to {os.path.join(folder, TICK_TIMING)} and action timing to "
                    f"{os.path.join(folder, ACTION_TIMING)}")
    return found


def _write_coverage(context: ScenarioContext, result: ScenarioResult, logger: Logger) -> None:
    """Keep the run's samples: ``coverage.json`` in its folder, and one JUnit property per item sampled."""
    sampler = context.coverage
    assert sampler is not None
    result.properties.update(sampler.properties())
    if not context.output_dir:
        return
    verdict = "passed" if result.passed else "error" if result.error else "failed"
    try:
        sampler.write(context.output_dir, verdict, result.message, result.duration)
    except Exception as exc:  # noqa: BLE001 - a sample the file cannot hold: say which, keep the run's verdict
        logger.error(f"coverage of '{result.name}' not written: {exc}")


def _reset_simulation(simulation: UserSimulation, run: PlannedRun) -> ScenarioResult | None:
    """Reset the simulation for ``run``; a failed result when that is impossible."""
    if getattr(simulation, "reset", None) is None:
        return None
    try:
        kwargs = reset_arguments(simulation, run.scenario.parameter_values(), run.name)
    except SimulationError as exc:
        return ScenarioResult(run.name, False, str(exc), output_dir=run.output_dir)
    try:
        simulation.reset(**kwargs)
    except Exception as exc:  # noqa: BLE001 - user code
        return ScenarioResult(run.name, False, f"simulation reset failed: {type(exc).__name__}: {exc}",
                              output_dir=run.output_dir)
    return None
