"""What ``scenario_execution`` does, start to end, without the command-line parsing.

load every parameter document → resolve the file once per document → check that every action has
an implementation → (``-l`` print the model) → (``-n`` stop) → (``--dot``) → run all planned
scenarios → write ``test.xml`` → run ``--post-run`` hooks → exit code.

Input problems raise :class:`~coverage_engine.errors.OscError` (rendered by the command) or
:class:`UsageProblem`; a parse or resolve error with ``--output-dir`` also leaves a ``test.xml`` with
one failing testcase. Only the run path imports py_trees (and rich only for ``-t``).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from coverage_engine.domains import drawn_units_of
from coverage_engine.errors import OscError, UserError
from coverage_engine.results.files import RESULT_FILE
from coverage_engine.suffixes import SCE_SUFFIX
from executor.runtime.logger import Logger

if TYPE_CHECKING:   # imported on the paths that need them (-h and option errors stay quick)
    from coverage_engine.files.sce import SceDocument
    from coverage_engine.resolve.model import ScenarioFile
    from coverage_engine.results.run_report import ReportNames
    from executor.runtime.planned_runs import PlannedRun
    from executor.runtime.session import SessionOutcome
    from executor.runtime.simulation import UserSimulation

    #: A resolved file and the output folder of each of its scenarios (``_output_dir`` of one document).
    LoadedFile = tuple[ScenarioFile, dict[str, str]]

EXIT_OK = 0
EXIT_FAILED = 1


class UsageProblem(UserError):
    """A bad option value or combination (reported as ``error: …``)."""


class ExecutionRequest:
    """The options of one ``scenario_execution`` call (a plain class: it is created on every start)."""

    def __init__(self, scenario: str, output_dir: str | None = None, dry_run: bool = False,
                 log_model: bool = False, debug: bool = False, live_tree: bool = False, dot: bool = False,
                 step_duration: float = 0.1, parameter_file: str | None = None, create_template: bool = False,
                 post_run: tuple[str, ...] = (), simulation: str | None = None, per_scenario: bool = False,
                 bt_log: bool = False, tick_log: bool = False) -> None:
        self.scenario = scenario
        self.output_dir = output_dir
        self.dry_run = dry_run
        self.log_model = log_model
        self.debug = debug
        self.live_tree = live_tree
        self.dot = dot
        self.step_duration = step_duration
        self.parameter_file = parameter_file
        self.create_template = create_template
        self.post_run = tuple(post_run)
        self.simulation = simulation
        self.per_scenario = per_scenario
        self.bt_log = bt_log
        self.tick_log = tick_log


def _check_options(request: ExecutionRequest) -> None:
    step = request.step_duration
    if isinstance(step, bool) or not isinstance(step, (int, float)) or not math.isfinite(step) or step <= 0:
        raise UsageProblem(f"--step-duration must be a positive, finite number of seconds, got {step!r}")
    for flag, asked in (("--bt-log", request.bt_log), ("--tick-log", request.tick_log)):
        if asked and not request.output_dir and not request.dry_run:
            raise UsageProblem(f"{flag} writes into the output folder: give --output-dir")
    if not request.post_run:
        return
    import shutil

    from executor.children.hooks import split_hook

    for hook in request.post_run:
        try:
            program = split_hook(hook)[0]
        except ValueError as exc:
            raise UsageProblem(f"--post-run '{hook}': {exc}") from exc
        if shutil.which(program) is None and not (os.path.isfile(program) and os.access(program, os.X_OK)):
            raise UsageProblem(f"--post-run '{hook}': '{program}' is not an executable file or command")


#: From this many parameter documents on, resolving them shows its progress on a terminal.
PROGRESS_FROM = 2000


def _load(request: ExecutionRequest, logger: Logger, output_root: str | None = None) -> list[LoadedFile]:
    """Resolve the file once per parameter document: ``[(ScenarioFile, {scenario: _output_dir})]``.

    A parameter-file error without a location is pointed at the file (at the key, when the message
    names one); an empty document is said once, as it runs every scenario with its defaults.
    """
    from coverage_engine.errors import ParameterFileError
    from coverage_engine.files.loader import load_scenario_file
    from executor.runtime.planned_runs import split_output_dirs

    documents: Sequence[dict | None] = [None]
    path = request.parameter_file
    if path:
        from coverage_engine.files.parameters import read_parameter_documents

        documents = read_parameter_documents(path)
        if not documents:
            documents = [None]
        for index, document in enumerate(documents):
            if not document:
                which = f"document {index + 1} is empty" if len(documents) > 1 else "it holds no parameters"
                logger.warning(f"{path}: {which}: scenarios run with their defaults")
    loaded = []
    progress = len(documents) >= PROGRESS_FROM and sys.stderr.isatty()
    for index, document in enumerate(documents):
        if progress and index % 1000 == 0:
            print(f"\rresolving parameter document {index + 1} of {len(documents)}", end="", file=sys.stderr,
                  flush=True)
        try:
            overrides, dirs = split_output_dirs(document, output_root)
            loaded.append((load_scenario_file(request.scenario, overrides), dirs))
        except ParameterFileError as exc:
            if path and exc.location is None:
                from executor.runtime.parameter_locations import locate

                exc.location, exc.source_line = locate(path, index, exc.message)
            raise
    if progress:
        print(f"\rresolved {len(documents)} parameter documents" + " " * 12, file=sys.stderr, flush=True)
    return loaded


def _variant(scenario: str) -> SceDocument | None:
    """The ``.sce`` document of a variant (None for an ``.osc``, or a ``.sce`` that cannot be read)."""
    if not scenario.endswith(SCE_SUFFIX):
        return None
    from coverage_engine.files.sce import read_sce

    try:
        return read_sce(scenario)
    except OscError:
        return None


def _located(exc: OscError, scenario: str) -> str:
    """The one-line message of a file that did not load, naming where (for a variant, the ``.osc`` line too)."""
    from coverage_engine.files.sce import variant_lines

    document = _variant(scenario) if exc.location is not None else None
    return exc.located(variant_lines(document).place if document is not None else str)


def report_names(scenario: str, runs: Sequence[PlannedRun] = (), document: SceDocument | None = None) -> ReportNames:
    """How ``test.xml`` names the runs of ``scenario`` (a variant's names come from its ``.sce`` header,
    ``document`` when it was read already)."""
    from coverage_engine.results.run_report import report_names as names_for

    document = document or _variant(scenario)
    variant = (document.source, document.scenario, document.assignment,
               drawn_units_of(document.domains)) if document is not None else None
    return names_for(scenario, [(run.name, run.scenario.name) for run in runs], variant)


def execute(request: ExecutionRequest) -> int:
    """Do everything the command does; returns the exit code."""
    logger = Logger("scenario_execution", debug=request.debug)
    _check_options(request)
    if request.create_template:
        if not request.parameter_file:
            raise UsageProblem("--create-scenario-parameter-file-template needs --scenario-parameter-file FILE "
                               "(the template is written there)")
        from coverage_engine.files.parameters import write_parameter_template

        write_parameter_template(request.scenario, request.parameter_file)
        logger.info(f"Wrote scenario parameter template {request.parameter_file}")
        return EXIT_OK

    output_root = os.path.abspath(request.output_dir) if request.output_dir else None
    if output_root and not request.dry_run:
        try:
            os.makedirs(output_root, exist_ok=True)
        except OSError as exc:
            raise UsageProblem(f"cannot create output directory '{request.output_dir}': {exc.strerror}") from exc
        stale = os.path.join(output_root, RESULT_FILE)
        if os.path.isfile(stale):
            os.remove(stale)

    try:
        loaded = _load(request, logger, output_root)
        from executor.actions.registry import check_actions_available

        check_actions_available(s for scenario_file, _ in loaded for s in scenario_file.scenarios)
    except OscError as exc:
        if output_root and not request.dry_run:
            from coverage_engine.results.run_report import parse_error_result, write_results

            write_results(output_root, [parse_error_result(request.scenario, _located(exc, request.scenario),
                                                           str(exc))], report_names(request.scenario))
        raise

    if request.log_model:
        from coverage_engine.resolve.printer import format_model

        for scenario_file, _ in loaded:
            print(format_model(scenario_file), flush=True)
    if request.dry_run:
        return EXIT_OK
    return _run(request, loaded, output_root, logger)


def _run(request: ExecutionRequest, loaded: list[LoadedFile], output_root: str | None, logger: Logger) -> int:
    from coverage_engine.files.sce import variant_lines
    from coverage_engine.resolve.evaluate import add_import_paths
    from executor.runtime.planned_runs import RunOrigin, plan_runs
    from executor.runtime.session import SessionOptions, run_session

    scenario_dir = os.path.dirname(os.path.abspath(request.scenario))
    # A .sce file's user modules live beside the .osc it was generated from: the model says where.
    model_dirs = [d for scenario_file, _ in loaded for d in scenario_file.search_paths]
    add_import_paths([os.getcwd(), scenario_dir, *model_dirs])
    if request.scenario.endswith(SCE_SUFFIX) and model_dirs and os.path.isdir(model_dirs[0]):
        scenario_dir = os.path.abspath(model_dirs[0])  # a variant's files (maps, models) sit beside its source
    runs = plan_runs(loaded, output_root)
    document = _variant(request.scenario)
    names = report_names(request.scenario, runs, document) if output_root else None
    origin = RunOrigin(request.scenario) if document is None else \
        RunOrigin(request.scenario, os.path.splitext(os.path.basename(request.scenario))[0], document.assignment,
                  variant_lines(document))
    if not runs:
        logger.error(f"{request.scenario}: no scenario to run (the file declares none)")
        return EXIT_FAILED

    simulation = _load_simulation(request, runs, output_root, names) if request.simulation else None
    if request.dot:
        from executor.runtime.dot import write_dot_files

        write_dot_files(runs, output_root or os.getcwd(), logger)

    live = None
    if request.live_tree:
        from executor.runtime.live import LiveTree

        live = LiveTree()
    report = None
    if output_root:
        from coverage_engine.results.run_report import ReportWriter

        report = ReportWriter(output_root, request.per_scenario, names)
    options = SessionOptions(tick_period=request.step_duration, simulation=simulation, input_dir=scenario_dir,
                             output_root=output_root, debug=request.debug,
                             observer_factory=live.observers if live else None,
                             on_result=report.update if report else None, origin=origin,
                             scenario_file=request.scenario, bt_log=request.bt_log, tick_log=request.tick_log)
    try:
        outcome = run_session(runs, options, logger)
    finally:
        if live is not None:
            live.close()

    if report is not None:  # what the last update did not see (the aborted and skipped scenarios)
        for path in report.update(outcome.results, final=True):
            logger.debug(f"wrote {path}")
    return _finish(request, outcome, output_root, logger)


def _load_simulation(request: ExecutionRequest, runs: list[PlannedRun], output_root: str | None,
                     names: ReportNames | None) -> UserSimulation:
    """The ``--simulation`` object; one that cannot load is a usage problem, and with ``-o`` every run's
    testcase says why nothing ran (CI sees it)."""
    from executor.runtime.simulation import SimulationError, load_simulation, simulation_dt

    assert request.simulation is not None
    try:
        simulation = load_simulation(request.simulation)
        simulation_dt(simulation)
    except SimulationError as exc:
        if output_root:
            from coverage_engine.results.run_report import write_grouped
            from coverage_engine.results.scenario_result import ScenarioResult

            write_grouped([ScenarioResult(r.name, False, str(exc), output_dir=r.output_dir) for r in runs],
                          output_root, request.per_scenario, names)
        raise UsageProblem(str(exc)) from exc
    return simulation


def _finish(request: ExecutionRequest, outcome: SessionOutcome, output_root: str | None, logger: Logger) -> int:
    """After the runs: the post-run hooks (not after an abort), the closing line, the exit code."""
    if outcome.aborted:
        if request.post_run:
            logger.warning("aborted: --post-run commands skipped")
        return 128 + outcome.aborted
    if request.post_run:
        from executor.children.hooks import run_post_hooks

        def announce(command: str) -> None:
            logger.info(f"Running post-run: {command}")
            sys.stdout.flush()

        run_post_hooks(request.post_run, output_root or os.getcwd(), announce=announce, report=logger.error)
    failed = [r.name for r in outcome.results if not r.passed]
    if failed:
        logger.error(f"{len(failed)} of {len(outcome.results)} scenario(s) failed: {', '.join(failed)}")
    return EXIT_OK if outcome.passed else EXIT_FAILED
