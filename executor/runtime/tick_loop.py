"""Tick one scenario's tree to its end and report a :class:`ScenarioResult`.

The loop: (simulation: ``step()`` and advance the clock) → tick the tree → let observers look at it
(live view) → stop when the root has finished, or ``emit end``/``emit fail`` fired. Without a
simulation the loop keeps a fixed tick period on the wall clock; with one it never sleeps. On
failure the tree is rendered with its statuses (the last snapshot) before it is stopped, so
``test.xml`` shows where the scenario stood. Stopping then terminates running behaviours, and every
action's ``shutdown()`` runs (processes are ended) whatever happened.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import py_trees
from py_trees.common import Status

from coverage_engine.errors import OscError
from coverage_engine.location import Location
from coverage_engine.resolve.evaluate import EvaluationError
from coverage_engine.resolve.model import Scenario
from coverage_engine.results.scenario_result import ScenarioResult
from executor.actions.base import ActionError
from executor.runtime.builder import build_tree
from executor.runtime.context import Aborted, ScenarioContext, ScenarioEnd
from executor.runtime.recording import Recorder
from executor.runtime.simulation import SimulationClock, SimulationError, SimulationStepError, UserSimulation

TickObserver = Callable[[py_trees.behaviour.Behaviour], None]


def snapshot(root: py_trees.behaviour.Behaviour) -> str:
    """The tree as text with each behaviour's status and feedback message."""
    try:
        return py_trees.display.unicode_tree(root, show_status=True)
    except Exception as exc:  # noqa: BLE001 - a rendering problem must not hide the real failure
        return f"(no tree snapshot: {exc})"


def describe_error(exc: BaseException, place: Callable[[Location], str] = str) -> str:
    """One line for an exception raised while a scenario ran, its location named by ``place``."""
    if isinstance(exc, OscError):
        return exc.located(place)
    if isinstance(exc, SimulationError):
        return str(exc)
    if isinstance(exc, (ActionError, EvaluationError)):
        location = getattr(exc, "location", None)
        return f"{place(location)}: {exc}" if location else str(exc)
    return f"{type(exc).__name__}: {exc}"


def _leaf_with(root: py_trees.behaviour.Behaviour, status: Status) -> py_trees.behaviour.Behaviour | None:
    """The first behaviour in tick order with ``status`` none of whose children has it (where it happened)."""
    for node in root.iterate():                      # children come before their parent
        if node.status is status and not any(child.status is status for child in node.children):
            return node
    return None


def where(root: py_trees.behaviour.Behaviour | None, status: Status,
          place: Callable[[Location], str] = str) -> tuple[str, str]:
    """``("'name' at file:line:col", feedback)`` of the behaviour that has ``status`` (``("", "")`` if none)."""
    node = None if root is None else _leaf_with(root, status)
    if node is None or node is root:
        return "", ""
    location = getattr(node, "osc_location", None)
    return f"'{node.name}'" + (f" at {place(location)}" if location else ""), node.feedback_message or ""


class ScenarioRunner:
    """Runs one scenario: build, set up, tick, tear down."""

    def __init__(self, scenario: Scenario, context: ScenarioContext, *, name: str | None = None,
                 tick_period: float = 0.1, simulation: UserSimulation | None = None,
                 observers: list[TickObserver] | None = None,
                 setup_kwargs: dict | None = None, skip_idle_ticks: bool = True,
                 recorders: list[Recorder] | None = None) -> None:
        self.scenario = scenario
        self.context = context
        self.name = name or scenario.name
        self.tick_period = tick_period
        self.simulation = simulation
        self.observers = observers or []
        self.setup_kwargs = setup_kwargs or {}
        self.root: py_trees.behaviour.Behaviour | None = None
        self.ticks = 0
        #: step-based mode: do not tick while only waits run (see executor.runtime.quiescence)
        self.skip_idle_ticks = skip_idle_ticks
        #: --bt-log / --tick-log (executor.runtime.recording); empty unless asked for
        self.recorders = recorders or []

    # -- phases ------------------------------------------------------------------------------------

    def _setup(self) -> None:
        context = self.context
        context.init_variables(self.scenario)
        if self.scenario.coverage:
            from executor.runtime.coverage_sampling import CoverageSampler

            context.coverage = CoverageSampler(self.scenario, context.variables, run_name=self.name,
                                               origin=context.origin)
        self.root = build_tree(self.scenario, context)
        self.root.name = self.name
        for recorder in self.recorders:     # before setup, so the actions' own setup is timed
            recorder.started(self.root)
        kwargs = dict(self.setup_kwargs, logger=context.logger, input_dir=context.input_dir,
                      output_dir=context.output_dir, clock=context.clock, context=context,
                      tick_period=self.tick_period)
        if self.simulation is not None:
            kwargs["simulation"] = self.simulation
        for node in self.root.iterate():
            node.setup(**kwargs)

    def _tick_loop(self) -> Status:
        root = self.root
        assert root is not None, "set up before ticking"
        simulation = self.simulation
        observers = self.observers
        if simulation is not None:
            return self._step_loop(root, simulation, observers)
        period = self.tick_period
        next_tick = time.monotonic()
        while True:
            if self._tick(root, observers):
                return root.status
            next_tick += period
            delay = next_tick - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            else:
                next_tick = time.monotonic()

    def _tick(self, root: py_trees.behaviour.Behaviour, observers: list[TickObserver]) -> bool:
        """Tick the tree once and show it to the observers; True when the tree has finished."""
        recorders = self.recorders
        if recorders:
            for recorder in recorders:
                recorder.before_tick()
            root.tick_once()
            for recorder in recorders:
                recorder.after_tick(root)
        else:
            root.tick_once()
        self.ticks += 1
        for observe in observers:
            observe(root)
        return root.status is not Status.RUNNING

    def _step_loop(self, root: py_trees.behaviour.Behaviour, simulation: UserSimulation,
                   observers: list[TickObserver]) -> Status:
        """Step-based: one ``step()`` per ``dt``; the tree is ticked whenever a tick can matter.

        Between ticks in which only time/event/condition waits run, nothing can change before the
        earliest deadline (:func:`~executor.runtime.quiescence.next_wake`), so the simulation is
        stepped without ticking until then — the same result as ticking every step.
        """
        from executor.runtime.quiescence import next_wake

        clock = self.context.clock
        assert isinstance(clock, SimulationClock), "a simulation runs on a simulation clock"
        step = simulation.step
        advance = clock.advance
        now = clock.now
        wake = -1.0
        while True:
            try:
                step()
            except Exception as exc:  # noqa: BLE001 - user code; named, the scenario fails
                raise SimulationStepError(
                    f"simulation step ({type(simulation).__name__}.step()) raised {type(exc).__name__}: {exc}") from exc
            advance()
            if now() < wake:
                continue
            if self._tick(root, observers):
                return root.status
            if self.skip_idle_ticks:
                wake = next_wake(root)

    def _teardown(self) -> None:
        if self.root is None:
            return
        try:
            self.root.stop(Status.INVALID)
        except Exception as exc:  # noqa: BLE001 - keep shutting down
            self.context.logger.error(f"stopping the tree: {describe_error(exc)}")
        for node in self.root.iterate():
            shutdown = getattr(node, "shutdown", None)
            if shutdown is None:
                continue
            try:
                shutdown()
            except Exception as exc:  # noqa: BLE001 - one action's cleanup must not stop the others
                where = "" if isinstance(exc, OscError) else f"shutdown of '{node.name}': "
                self.context.logger.error(where + describe_error(exc))

    # -- the whole run -----------------------------------------------------------------------------

    def run(self) -> ScenarioResult:
        """Run to the end and return the result; raises :class:`RunAborted` (result inside) on a signal."""
        logger = self.context.logger
        logger.info(f"Executing scenario '{self.name}'")
        start = time.monotonic()
        result = ScenarioResult(self.name, False, start_time=time.time(), output_dir=self.context.output_dir)
        signum = 0
        ticking = False
        place = self.context.origin.place if self.context.origin is not None else str
        try:
            self._setup()
            ticking = True
            status = self._tick_loop()
            result.passed = status is Status.SUCCESS
            if not result.passed:
                failed, why = where(self.root, Status.FAILURE, place)
                result.message = (f"{failed} failed" + (f": {why}" if why else "")) if failed else \
                    f"the behaviour tree of scenario '{self.scenario.name}' at {place(self.scenario.location)} failed"
        except ScenarioEnd as end:
            result.passed = end.success
            result.message = "" if end.success else _located(end, place)
            _mark_path(end.behaviour, Status.SUCCESS if end.success else Status.FAILURE)
        except (Aborted, KeyboardInterrupt) as exc:
            signum = exc.signum if isinstance(exc, Aborted) else 2
            running = where(self.root, Status.RUNNING, place)[0] if ticking else ""
            result.message = f"aborted by {_signal_name(signum)}" + (f" while {running} ran" if running else "")
            result.aborted = True
        except Exception as exc:  # noqa: BLE001 - anything raised by actions, expressions or plugins
            described = describe_error(exc, place)
            result.message = described if ticking else f"setup failed: {described}"
            if logger.debug_enabled:
                import traceback

                logger.debug(traceback.format_exc())
        finally:
            if not result.passed and self.root is not None and ticking:
                result.output = snapshot(self.root)
            self._teardown()
            for recorder in self.recorders:
                recorder.close()
        if self.context.coverage is not None and ticking and not result.aborted:
            try:
                self.context.coverage.finish(result.passed)
            except Exception as exc:  # noqa: BLE001 - an item's expression failed: say so, keep the verdict
                logger.error(f"coverage of '{self.name}': {describe_error(exc)}")
        result.duration = time.monotonic() - start
        if result.passed:
            logger.info(f"Scenario '{self.name}' succeeded.")
        else:
            logger.error(f"Scenario '{self.name}' failed: {result.message}")
        if signum:
            raise RunAborted(result, signum)
        return result


def _signal_name(signum: int) -> str:
    import signal

    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


def _located(end: ScenarioEnd, place: Callable[[Location], str]) -> str:
    """The failure message of ``emit fail`` with where it stands (``emit fail at bad.osc:6:9``)."""
    location = getattr(end.behaviour, "osc_location", None)
    return f"{end.message} at {place(location)}" if location is not None else end.message


def _mark_path(behaviour: py_trees.behaviour.Behaviour | None, status: Status) -> None:
    """Show the behaviour that ended the scenario, and the composites above it, with the end status."""
    while behaviour is not None:
        behaviour.status = status
        behaviour = behaviour.parent


class RunAborted(Exception):  # noqa: N818 - carries the recorded result out of the loop
    """A run was aborted by a signal; ``result`` is the recorded (failed) result."""

    def __init__(self, result: ScenarioResult, signum: int) -> None:
        super().__init__("aborted")
        self.result = result
        self.signum = signum
