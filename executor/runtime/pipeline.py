"""What ``scenario_execution`` does, start to end, without the command-line parsing.

load every parameter document → resolve the file once per document → check that every action has
an implementation → (``-l`` print the model) → (``-n`` stop) → (``--dot``) → run all planned
scenarios → write ``test.xml`` → run ``--post-run`` hooks → exit code.

Input problems raise :class:`~coverage_engine.errors.OscError` (rendered by the command) or
:class:`UsageProblem`; a parse or resolve error with ``--output-dir`` also leaves a ``test.xml`` with
one failing testcase. Only the run path imports py_trees (and rich only for ``-t``).
"""

from __future__ import annotations

import os

from coverage_engine.errors import OscError
from executor.runtime.logger import Logger

EXIT_OK = 0
EXIT_FAILED = 1


class UsageProblem(Exception):
    """A bad option value or combination (reported as ``error: …``)."""


class ExecutionRequest:
    """The options of one ``scenario_execution`` call (a plain class: it is created on every start)."""

    def __init__(self, scenario: str, output_dir: str | None = None, dry_run: bool = False,
                 log_model: bool = False, debug: bool = False, live_tree: bool = False, dot: bool = False,
                 step_duration: float = 0.1, parameter_file: str | None = None, create_template: bool = False,
                 post_run: tuple[str, ...] = (), simulation: str | None = None, per_scenario: bool = False) -> None:
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


def _check_options(request: ExecutionRequest) -> None:
    if not request.step_duration or request.step_duration <= 0:
        raise UsageProblem(f"--step-duration must be a positive number of seconds, got {request.step_duration}")
    if not request.post_run:
        return
    import shutil

    from executor.runtime.post_run import split_hook

    for hook in request.post_run:
        try:
            program = split_hook(hook)[0]
        except ValueError as exc:
            raise UsageProblem(f"--post-run '{hook}': {exc}") from exc
        if shutil.which(program) is None and not (os.path.isfile(program) and os.access(program, os.X_OK)):
            raise UsageProblem(f"--post-run '{hook}': '{program}' is not an executable file or command")


def _load(request: ExecutionRequest):
    """Resolve the file once per parameter document: ``[(ScenarioFile, {scenario: _output_dir})]``."""
    from coverage_engine.loader import load_scenario_file
    from executor.runtime.plan import split_output_dirs

    documents: list = [None]
    if request.parameter_file:
        from coverage_engine.parameters import read_parameter_documents

        documents = read_parameter_documents(request.parameter_file) or [None]
    split = [split_output_dirs(document) for document in documents]
    loaded = []
    for overrides, dirs in split:
        loaded.append((load_scenario_file(request.scenario, overrides), dirs))
    return loaded


def execute(request: ExecutionRequest) -> int:
    """Do everything the command does; returns the exit code."""
    logger = Logger("scenario_execution", debug=request.debug)
    _check_options(request)
    if request.create_template:
        if not request.parameter_file:
            raise UsageProblem("--create-scenario-parameter-file-template needs --scenario-parameter-file FILE "
                               "(the template is written there)")
        from coverage_engine.parameters import write_parameter_template

        write_parameter_template(request.scenario, request.parameter_file)
        logger.info(f"Wrote scenario parameter template {request.parameter_file}")
        return EXIT_OK

    output_root = os.path.abspath(request.output_dir) if request.output_dir else None
    if output_root and not request.dry_run:
        try:
            os.makedirs(output_root, exist_ok=True)
        except OSError as exc:
            raise UsageProblem(f"cannot create output directory '{request.output_dir}': {exc.strerror}") from exc
        stale = os.path.join(output_root, "test.xml")
        if os.path.isfile(stale):
            os.remove(stale)

    try:
        loaded = _load(request)
        from executor.actions.registry import check_actions_available

        check_actions_available(s for scenario_file, _ in loaded for s in scenario_file.scenarios)
    except OscError as exc:
        if output_root and not request.dry_run:
            from executor.junit import parse_error_result, write_results

            write_results(output_root, [parse_error_result(request.scenario, exc.message, str(exc))])
        raise

    if request.log_model:
        from coverage_engine.printer import format_model

        for scenario_file, _ in loaded:
            print(format_model(scenario_file), flush=True)
    if request.dry_run:
        return EXIT_OK
    return _run(request, loaded, output_root, logger)


def _run(request: ExecutionRequest, loaded, output_root: str | None, logger: Logger) -> int:
    from executor.runtime.plan import plan_runs
    from executor.runtime.session import SessionOptions, run_session

    simulation = None
    if request.simulation:
        from executor.simulation import SimulationError, load_simulation

        try:
            simulation = load_simulation(request.simulation)
        except SimulationError as exc:
            raise UsageProblem(str(exc)) from exc

    from coverage_engine.evaluate import add_import_paths

    scenario_dir = os.path.dirname(os.path.abspath(request.scenario))
    add_import_paths([os.getcwd(), scenario_dir])
    runs = plan_runs(loaded, output_root)
    if not runs:
        logger.error(f"{request.scenario}: no scenario to run (the file declares none)")
        return EXIT_FAILED
    if request.dot:
        from executor.runtime.dot import write_dot_files

        write_dot_files(runs, output_root or os.getcwd(), logger)

    live = None
    if request.live_tree:
        from executor.runtime.live import LiveTree

        live = LiveTree()
    options = SessionOptions(tick_period=request.step_duration, simulation=simulation, input_dir=scenario_dir,
                             output_root=output_root, debug=request.debug,
                             observer_factory=live.observers if live else None)
    try:
        outcome = run_session(runs, options, logger)
    finally:
        if live is not None:
            live.close()

    if output_root:
        from executor.junit import write_grouped

        for path in write_grouped(outcome.results, output_root, request.per_scenario):
            logger.debug(f"wrote {path}")
    if outcome.aborted:
        if request.post_run:
            logger.warning("aborted: --post-run commands skipped")
        return 128 + outcome.aborted
    if request.post_run:
        from executor.runtime.post_run import run_post_hooks

        run_post_hooks(request.post_run, output_root or os.getcwd(), logger)
    failed = [r.name for r in outcome.results if not r.passed]
    if failed:
        logger.error(f"{len(failed)} of {len(outcome.results)} scenario(s) failed: {', '.join(failed)}")
    return EXIT_OK if outcome.passed else EXIT_FAILED
