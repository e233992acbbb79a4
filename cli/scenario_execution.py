"""``scenario_execution``: run the scenarios of one ``.osc`` or ``.sce`` file.

Thin click command: it parses options, calls the front end (``coverage_engine``) and the runtime
(``executor``), and turns errors into one clear message and an exit code. Heavy packages (py_trees,
rich, the JUnit writer) are imported only on the paths that need them, so ``-n``, ``-l`` and the template
option stay fast.

Exit codes: 0 every scenario passed · 1 a scenario failed or the input is wrong · 2 usage error ·
128 + signal number when aborted by SIGINT/SIGTERM.
"""

from __future__ import annotations

import sys

import click

from coverage_engine.errors import OscError

EXIT_FAILED = 1


class Seconds(click.ParamType):
    """A positive, finite number of seconds up to a day (``inf``, ``nan``, 0 and negatives are usage errors)."""

    name = "seconds"
    maximum = 86400.0

    def convert(self, value, param, ctx):
        import math

        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(f"{value!r} is not a number of seconds", param, ctx)
        if not math.isfinite(number) or number <= 0:
            self.fail(f"{value!r} is not a positive, finite number of seconds", param, ctx)
        if number > self.maximum:
            self.fail(f"{value!r} is more than a day ({self.maximum:g} seconds)", param, ctx)
        return number


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("-d", "--debug", is_flag=True, help="Debug output (and tracebacks of internal errors).")
@click.option("-l", "--log-model", is_flag=True, help="Print the resolved model of the scenario file.")
@click.option("-t", "--live-tree", is_flag=True, help="Show the behaviour tree with its statuses while running.")
@click.option("-o", "--output-dir", type=click.Path(file_okay=False),
              help="Directory for results (test.xml); created with its parents.")
@click.option("-n", "--dry-run", is_flag=True, help="Parse and resolve only; execute nothing.")
@click.option("--dot", is_flag=True, help="Write <scenario>.dot (and .png/.svg when Graphviz is installed).")
@click.option("-s", "--step-duration", type=Seconds(), default=0.1, show_default=True,
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
@click.argument("scenario", required=False, type=click.Path(dir_okay=False))
def command(scenario, debug, log_model, live_tree, output_dir, dry_run, dot, step_duration,
            scenario_parameter_file, create_template, post_run, simulation, output_result_per_scenario):
    """Execute the scenarios of SCENARIO (an .osc or .sce file)."""
    if scenario is None:
        raise click.UsageError("missing the scenario file (an .osc or .sce file)")
    from executor.runtime.pipeline import ExecutionRequest

    request = ExecutionRequest(
        scenario=scenario, output_dir=output_dir, dry_run=dry_run, log_model=log_model, debug=debug,
        live_tree=live_tree, dot=dot, step_duration=step_duration, parameter_file=scenario_parameter_file,
        create_template=create_template, post_run=tuple(post_run), simulation=simulation,
        per_scenario=output_result_per_scenario)
    sys.exit(_guarded(request))


def _guarded(request) -> int:
    """Run and map every error to a message on stderr and an exit code."""
    from executor.runtime.pipeline import UsageProblem, execute

    debug = request.debug
    try:
        return execute(request)
    except (OscError, UsageProblem) as exc:
        if debug:
            import traceback

            traceback.print_exc()
        message = exc.render() if isinstance(exc, OscError) else f"error: {exc}"
        click.echo(message, err=True)
        return EXIT_FAILED
    except KeyboardInterrupt:
        click.echo("aborted", err=True)
        return 130
    except Exception as exc:  # noqa: BLE001 - the last line of defence: no traceback without -d
        if debug:
            import traceback

            traceback.print_exc()
        else:
            click.echo(f"error: internal error: {type(exc).__name__}: {exc} (run with -d for details)", err=True)
        return EXIT_FAILED


def main() -> None:
    """Console-script entry point."""
    command(prog_name="scenario_execution")


if __name__ == "__main__":
    main()
