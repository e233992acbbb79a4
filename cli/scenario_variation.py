"""``scenario_variation``: expand the ``keep(… in [...])`` constraints of an ``.osc`` into concrete ``.sce`` files.

Thin click command: options in, :mod:`cli._variation` does the work, errors become one clear
``file:line:col: error: …`` message and an exit code. Only click is imported at start-up; the front
end, rich and SQLAlchemy are imported when needed, so ``-h`` and errors are quick.

Exit codes: 0 every combination was generated · 1 the input is wrong, the store cannot be used, or
some combinations did not resolve (they are reported and skipped, the others are written) ·
2 usage error · 130 interrupted.
"""

from __future__ import annotations

import sys

import click

EXIT_FAILED = 1
EXIT_INTERRUPTED = 130


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("-o", "-t", "--output-dir", default="out", show_default=True, type=click.Path(file_okay=False),
              help="Directory for the generated .sce files (-t is an alias). Earlier .sce files there are replaced.")
@click.option("-d", "--debug", is_flag=True, help="Debug output (and tracebacks).")
@click.option("-l", "--log-model", is_flag=True, help="Print the resolved model of each generated variant.")
@click.option("--list", "list_only", is_flag=True,
              help="Print the assignments that would be generated; write nothing.")
@click.option("--store", metavar="URL",
              help="SQLAlchemy URL of the store (default: $SCENARIO_STORE, else .scenario_store.db here).")
@click.option("--scenario-parameter-file", type=click.Path(dir_okay=False),
              help="YAML file of scenario parameter values; each document is one more dimension.")
@click.argument("scenario", type=click.Path(dir_okay=False))
def command(scenario, output_dir, debug, log_model, list_only, store, scenario_parameter_file):
    """Generate one concrete scenario (.sce) per combination of the values listed in SCENARIO (.osc).

    Every keep(it.<param> in [v1, v2, ...]) is one dimension; the first varies slowest.
    """
    options = {"output_dir": output_dir, "debug": debug, "log_model": log_model, "list": list_only,
               "store": store, "scenario_parameter_file": scenario_parameter_file}
    sys.exit(_guarded(scenario, options))


def _guarded(scenario: str, options: dict) -> int:
    """Run, and map every error to a message on stderr and an exit code."""
    from coverage_engine.errors import OscError

    debug = options["debug"]
    try:
        from cli._variation import VariationStoreError, run

        return run(scenario, options)
    except (OscError, VariationStoreError) as exc:
        if debug:
            import traceback

            traceback.print_exc()
        click.echo(exc.render() if isinstance(exc, OscError) else f"error: {exc}", err=True)
        return EXIT_FAILED
    except KeyboardInterrupt:
        click.echo("interrupted", err=True)
        return EXIT_INTERRUPTED
    except OSError as exc:
        if debug:
            import traceback

            traceback.print_exc()
        click.echo(f"error: {exc}", err=True)
        return EXIT_FAILED
    except Exception as exc:  # noqa: BLE001 - last resort: a bug of ours, reported without a traceback
        if debug:
            raise
        click.echo(f"error: internal error: {type(exc).__name__}: {exc} (run with -d for details)", err=True)
        return EXIT_FAILED


def main() -> None:
    """Console script entry point."""
    command()


if __name__ == "__main__":  # pragma: no cover
    main()
