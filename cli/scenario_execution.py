"""``scenario_execution``: run the scenarios of one ``.osc`` or ``.sce`` file.

Thin click command: it parses the options into an
:class:`~executor.runtime.pipeline.ExecutionRequest` for the runtime (``executor``); errors become one
clear message and an exit code in :mod:`cli.boundary`. Heavy packages (py_trees, rich, the JUnit writer)
are imported only on the paths that need them, so ``-n``, ``-l`` and the template option stay fast.

Exit codes: 0 every scenario passed · 1 a scenario failed or the input is wrong · 2 usage error ·
128 + signal number when aborted by SIGINT/SIGTERM.
"""

from __future__ import annotations

import errno
import sys
from typing import Any, NoReturn

import click

from cli.boundary import Boundary
from cli.options import Seconds, debug_option

#: ``--step-duration`` above this is surely a mistake.
MAX_STEP_DURATION = 86400.0


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="scenario-coverage", message="%(prog)s %(version)s")
@debug_option
@click.option("-l", "--log-model", is_flag=True, help="Print the resolved model of the scenario file.")
@click.option("-t", "--live-tree", is_flag=True, help="Show the behaviour tree with its statuses while running.")
@click.option("-o", "--output-dir", type=click.Path(file_okay=False),
              help="Directory for results (test.xml); created with its parents.")
@click.option("-n", "--dry-run", is_flag=True, help="Parse and resolve only; execute nothing.")
@click.option("--dot", is_flag=True, help="Write <scenario>.dot (and .png/.svg when Graphviz is installed).")
@click.option("-s", "--step-duration", type=Seconds(maximum=MAX_STEP_DURATION), default=0.1, show_default=True,
              help="Seconds between two ticks of the behaviour tree (wall-clock mode).")
@click.option("--scenario-parameter-file", type=click.Path(dir_okay=False),
              help="YAML file overriding scenario parameters; several documents mean several runs.")
@click.option("--create-scenario-parameter-file-template", "create_template", is_flag=True,
              help="Write a template of all overridable parameters to --scenario-parameter-file.")
@click.option("--post-run", "post_run", multiple=True, metavar="CMD",
              help="Run 'CMD <output-dir>' after the scenarios (repeatable, in order).")
@click.option("--simulation", metavar="MODULE:CLASS",
              help="Step-based simulation: 'module.path:Class' or 'path/to/file.py:Class'.")
@click.option("--output-result-per-scenario", is_flag=True,
              help="Write test.xml into each scenario's output directory instead of one at the root.")
@click.option("--bt-log", is_flag=True,
              help="Record each behaviour's status over time to <output-dir>/behaviors.jsonl (needs --output-dir).")
@click.option("--tick-log", is_flag=True,
              help="Record tick timing to <output-dir>/tick_timing.csv and each action call's timing to "
                   "<output-dir>/action_timing.csv (needs --output-dir).")
@click.argument("scenario", required=False, type=click.Path(dir_okay=False))
def command(scenario: str | None, debug: bool, log_model: bool, live_tree: bool, output_dir: str | None,
            dry_run: bool, dot: bool, step_duration: float, scenario_parameter_file: str | None,
            create_template: bool, post_run: tuple[str, ...], simulation: str | None,
            output_result_per_scenario: bool, bt_log: bool, tick_log: bool) -> int:
    """Execute the scenarios of SCENARIO (an .osc or .sce file)."""
    if scenario is None:
        raise click.UsageError("missing the scenario file (an .osc or .sce file)")
    from executor.runtime.pipeline import ExecutionRequest, execute

    request = ExecutionRequest(
        scenario=scenario, output_dir=output_dir, dry_run=dry_run, log_model=log_model, debug=debug,
        live_tree=live_tree, dot=dot, step_duration=step_duration, parameter_file=scenario_parameter_file,
        create_template=create_template, post_run=tuple(post_run), simulation=simulation,
        per_scenario=output_result_per_scenario, bt_log=bt_log, tick_log=tick_log)
    return execute(request)


def main(args: list[str] | None = None) -> None:
    """Console-script entry point."""
    Boundary("scenario_execution").main(command, args)


#: The options of ``scenario_execution SCENARIO --output-dir DIR`` other than those two (parsed once).
_job_options: dict[str, object] | None = None


def run_job(scenario: str, output_dir: str) -> NoReturn:
    """Exactly ``main([scenario, "--output-dir", output_dir])``, with the command line parsed only once
    per process: the batch's built-in runner calls it in every job it forks.

    A forked job copies each memory page it writes, and click's parsing writes to about 150 pages of
    the server it was forked from that a run does not need; the options other than these two always
    take their defaults here, so they are parsed once, in the server. The two values still go through
    their click types (the same checks and messages), and the command runs in a click context with
    click's handling of Ctrl-C, end of input and a closed pipe.
    """
    boundary = Boundary("scenario_execution")
    sys.exit(boundary.guarded(lambda: _invoke_job(boundary, scenario, output_dir)))


def _invoke_job(boundary: Boundary, scenario: str, output_dir: str) -> object:
    global _job_options
    if _job_options is None:
        parsed = command.make_context("scenario_execution", [scenario, "--output-dir", output_dir], obj=boundary)
        _job_options = {k: v for k, v in parsed.params.items() if k not in ("scenario", "output_dir")}
    with click.Context(command, info_name="scenario_execution", obj=boundary) as context:
        given: dict[str, object] = {"scenario": scenario, "output_dir": output_dir}
        for parameter in command.params:
            if parameter.name in given:
                given[parameter.name] = parameter.type_cast_value(context, given[parameter.name])
        context.params = {**_job_options, **given}
        try:
            return command.invoke(context)
        except (EOFError, KeyboardInterrupt) as exc:     # as click's main does
            click.echo(file=sys.stderr)
            raise click.exceptions.Abort() from exc
        except OSError as exc:
            if exc.errno != errno.EPIPE:
                raise
            from click import utils as click_utils

            pacify: Any = getattr(click_utils, "PacifyFlushWrapper")  # noqa: B009 - untyped in click
            sys.stdout, sys.stderr = pacify(sys.stdout), pacify(sys.stderr)
            sys.exit(1)


if __name__ == "__main__":
    main()
