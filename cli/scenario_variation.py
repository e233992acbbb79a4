"""``scenario_variation``: expand the ``keep(… in [...])`` constraints of an ``.osc`` into concrete ``.sce`` files.

Thin click command: options in, :mod:`cli._variation` does the work, errors become one clear
``file:line:col: error: …`` message and an exit code. Only click is imported at start-up; the front
end, rich and SQLAlchemy are imported when needed, so ``-h`` and errors are quick.

Exit codes: 0 every combination was generated · 1 the input is wrong, the store cannot be used,
more combinations than ``--max-variants``, or some combinations did not resolve (they are reported
and skipped, the others are written) · 2 usage error · 130 interrupted (SIGINT or SIGTERM; the files
written so far are all recorded in the store).
"""

from __future__ import annotations

import signal
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
@click.option("--max-variants", type=click.IntRange(min=1), default=10_000_000, show_default=True, metavar="N",
              help="Refuse to start when the file has more combinations than N.")
@click.argument("scenario", type=click.Path(dir_okay=False))
def command(scenario, output_dir, debug, log_model, list_only, store, scenario_parameter_file, max_variants):
    """Generate one concrete scenario (.sce) per combination of the values listed in SCENARIO (.osc).

    Every keep(it.<param> in [v1, v2, ...]) is one dimension; the first varies slowest.
    """
    options = {"output_dir": output_dir, "debug": debug, "log_model": log_model, "list": list_only,
               "store": store, "scenario_parameter_file": scenario_parameter_file, "max_variants": max_variants}
    sys.exit(_guarded(scenario, options))


def _guarded(scenario: str, options: dict) -> int:
    """Run, and map every error to a message on stderr and an exit code."""
    from coverage_engine.errors import OscError

    debug = options["debug"]
    previous = _terminate_like_interrupt()
    try:
        from cli._variation import TooManyVariants, VariationStoreError, run

        return run(scenario, options)
    except (OscError, VariationStoreError, TooManyVariants) as exc:
        if debug:
            import traceback

            traceback.print_exc()
        if isinstance(exc, OscError):
            click.echo(exc.render(), err=True)
        else:
            click.echo(str(exc) if isinstance(exc, TooManyVariants) else f"error: {exc}", err=True)
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
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _terminate_like_interrupt():
    """SIGTERM stops the command like Ctrl-C does (exit 130, no traceback); returns the previous handler.

    While files are written, :mod:`cli._variation` takes both signals over to stop cleanly.
    """
    def interrupt(_signum, _frame):
        raise KeyboardInterrupt

    try:
        return signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread (e.g. CliRunner in a thread)
        return None


def main() -> None:
    """Console script entry point."""
    command()


if __name__ == "__main__":  # pragma: no cover
    main()
