"""Run-time state of one scenario: variables, events, clock, directories, and how it ends.

Behaviours and actions share one :class:`ScenarioContext` per scenario run. Variables are kept by
:attr:`coverage_engine.resolve.model.Variable.key`, so nested ``var`` members (``actor.struct.count``) are
as easy to reach as scenario-level ones. ``emit end``/``emit fail`` raise :class:`ScenarioEnd`, which
unwinds the tick at once: nothing after them runs, in the same serial or anywhere else.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from coverage_engine.resolve.evaluate import evaluate
from coverage_engine.resolve.model import Expr, Scenario
from executor.runtime.logger import Logger
from executor.runtime.planned_runs import RunOrigin

if TYPE_CHECKING:
    import py_trees

    from executor.runtime.coverage_sampling import CoverageSampler
    from executor.runtime.simulation import Clock


class ScenarioEnd(Exception):  # noqa: N818 - a control-flow signal, not an error
    """``emit end`` (success) or ``emit fail`` (failure): ends the scenario immediately."""

    def __init__(self, success: bool, message: str = "", behaviour: py_trees.behaviour.Behaviour | None = None) -> None:
        super().__init__(message or ("end" if success else "fail"))
        self.success = success
        self.message = message
        #: the behaviour that ended the scenario (marked in the failure snapshot)
        self.behaviour = behaviour


class Aborted(BaseException):  # noqa: N818 - raised by the signal handler; not an Exception,
    # so no ``except Exception`` in an action can swallow it
    """SIGINT/SIGTERM arrived: the running scenario is recorded as failed and nothing else runs."""

    def __init__(self, signum: int) -> None:
        super().__init__(f"aborted by signal {signum}")
        self.signum = signum


class ScenarioContext:
    """Everything a running scenario's behaviours share.

    ``variables`` maps variable keys to current values, ``events`` holds the emitted events and
    ``processes`` the run_process actions by name (label), for process_log_check.
    """

    def __init__(self, name: str, clock: Clock, logger: Logger, input_dir: str | None = None,
                 output_dir: str | None = None, simulation: object | None = None,
                 origin: RunOrigin | None = None) -> None:
        self.name = name
        self.clock = clock
        self.logger = logger
        self.input_dir = input_dir
        self.output_dir = output_dir
        self.simulation = simulation
        self.origin = origin
        self.variables: dict[str, object] = {}
        self.events: set[str] = set()
        self.processes: dict[str, list] = {}
        #: The run's cover()/record() sampler (executor.runtime.coverage_sampling), when it has items.
        self.coverage: CoverageSampler | None = None
        #: How close the closest ``compare`` came to flipping (see executor.actions.compare), None before any.
        self.check_margin: float | None = None

    def note_check_margin(self, margin: float) -> None:
        """Keep the smallest margin a check has had so far."""
        if self.check_margin is None or margin < self.check_margin:
            self.check_margin = margin

    def init_variables(self, scenario: Scenario) -> None:
        """Give every ``var`` its initial value (in declaration order, so one may use another)."""
        for variable in scenario.variables:
            initial = variable.initial
            self.variables[variable.key] = None if initial is None else evaluate(initial, self.variables)

    def value(self, expr: Expr) -> object:
        """The current value of a model expression."""
        return evaluate(expr, self.variables)
