"""``scenario_coverage``: report the coverage of a batch (or of one run) in the terminal, as JSON or as HTML.

    scenario_coverage report RESULTS [--store URL] [--batch ID] [--plan F] [-o FILE] [--fail-under PCT]
    scenario_coverage html   RESULTS [...] [-o coverage.html]
    scenario_coverage json   RESULTS [...] [-o FILE]

Thin click commands: the reading, merging and grading is :mod:`coverage_engine.coverage` (and
:mod:`executor.coverage_source` for ``--store``); here options are parsed and errors become one line.
Exit codes: 0 · 1 the grade is below ``--fail-under``, or the results, plan or store cannot be used ·
2 usage error (the command line itself).
"""

from __future__ import annotations

import os
import sys
import time
import traceback

import click

from coverage_engine.errors import OscError
from store.database import StoreError

PROG = "scenario_coverage"
EXIT_BELOW = 1
EXIT_USAGE = 2
CONTEXT = {"help_option_names": ["-h", "--help"]}


def _common(func):
    options = [
        click.argument("results", required=False, type=click.Path(file_okay=True)),
        click.option("--store", "store_url", metavar="URL",
                     help="Read the batch from this store (SQLAlchemy URL) instead of the results folder."),
        click.option("--batch", "batch_id", type=click.IntRange(min=1), help="With --store: the batch "
                     "(default: the latest batch of RESULTS, or the latest batch)."),
        click.option("--plan", "plan_file", type=click.Path(dir_okay=False), metavar="FILE",
                     help="YAML plan: item weights and per-bucket hit targets (at_least)."),
        click.option("--fail-under", type=click.FloatRange(0, 100), metavar="PCT",
                     help="Exit 1 when the overall grade is below PCT percent."),
        click.option("-d", "--debug", is_flag=True, help="Show tracebacks of errors."),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def _report(results, store_url, batch_id, plan_file):
    from coverage_engine.coverage.grading import build_report
    from coverage_engine.coverage.plan import read_plan

    if store_url is None and results is None:
        raise click.UsageError("missing RESULTS: a results folder, or a run's output folder (or give --store)")
    if batch_id is not None and store_url is None:
        raise click.UsageError("--batch needs --store")
    plan = read_plan(plan_file) if plan_file else None
    if store_url is not None:
        from executor.coverage_source import store_source

        source = store_source(store_url, results, batch_id)
    else:
        from coverage_engine.coverage.results_folder import read_results_folder

        source = read_results_folder(results)
    return build_report(source, plan)


def _gate(report, fail_under) -> int:
    """``--fail-under``: one comparison on the computed grade."""
    if fail_under is None:
        return 0
    grade = report.grade if report.grade is not None else 0.0
    if grade < fail_under:
        click.echo(f"{PROG}: coverage grade {grade:.1f} % is below --fail-under {fail_under:g} %", err=True)
        return EXIT_BELOW
    return 0


def _output_path(output: str) -> str:
    if os.path.isdir(output):
        raise click.UsageError(f"-o {output}: is a folder (give a file name)")
    return output


@click.command(context_settings=CONTEXT)
@_common
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write the (plain) report to FILE.")
def report_command(results, store_url, batch_id, plan_file, fail_under, debug, output):
    """Print the coverage of RESULTS: items, buckets, grades, holes and failing runs."""
    from rich.console import Console

    from coverage_engine.coverage.render_text import render_text

    report = _report(results, store_url, batch_id, plan_file)
    if output:
        import io

        from coverage_engine.coverage.atomic import write_text_atomically

        buffer = io.StringIO()
        render_text(report, Console(file=buffer, width=120, color_system=None, force_terminal=False), plain=True)
        write_text_atomically(_output_path(output), buffer.getvalue())
    else:
        terminal = sys.stdout.isatty()
        console = Console(no_color=bool(os.environ.get("NO_COLOR")) or None, width=None if terminal else 120,
                          force_terminal=terminal, highlight=False)
        render_text(report, console, plain=not terminal)
    return _gate(report, fail_under)


@click.command(context_settings=CONTEXT)
@_common
@click.option("-o", "--output", type=click.Path(dir_okay=False), default="coverage.html", show_default=True,
              help="The HTML file to write (one self-contained file).")
def html_command(results, store_url, batch_id, plan_file, fail_under, debug, output):
    """Write the coverage of RESULTS as one self-contained HTML page (no network needed to view it)."""
    from coverage_engine.coverage.atomic import write_text_atomically
    from coverage_engine.coverage.render_html import render_html

    path = _output_path(output)
    report = _report(results, store_url, batch_id, plan_file)
    folder = os.path.dirname(os.path.abspath(path))
    text = render_html(report, output_dir=folder, generated=time.strftime("%Y-%m-%d %H:%M"))
    write_text_atomically(path, text)
    grade = "no graded item" if report.grade is None else f"grade {report.grade:.1f} %"
    click.echo(f"wrote {path} ({grade}, {len(report.runs)} run(s))")
    return _gate(report, fail_under)


@click.command(context_settings=CONTEXT)
@_common
@click.option("-o", "--output", type=click.Path(dir_okay=False), default="-", show_default=True,
              help="The JSON file to write ('-': standard output).")
def json_command(results, store_url, batch_id, plan_file, fail_under, debug, output):
    """Write the coverage of RESULTS as JSON (format scenario-coverage/report, see docs/coverage.md)."""
    from coverage_engine.coverage.atomic import write_text_atomically
    from coverage_engine.coverage.render_json import render_json

    report = _report(results, store_url, batch_id, plan_file)
    text = render_json(report)
    if output == "-":
        sys.stdout.write(text)
    else:
        write_text_atomically(_output_path(output), text)
    return _gate(report, fail_under)


COMMANDS = {"report": report_command, "html": html_command, "json": json_command}


@click.group(context_settings=CONTEXT, commands=COMMANDS)
def group():
    """Report the coverage of a batch's results folder (or of one run's folder, or of a batch in the store)."""


def _fail(message: str, code: int) -> int:
    lines = [line.strip() for line in str(message).splitlines()
             if line.strip() and not line.startswith("(Background on this error")]
    click.echo(f"{PROG}: error: {' '.join(lines)}", err=True)
    return code


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point: run a subcommand and map every error to a message and an exit code."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "-d" in args or "--debug" in args
    try:
        code = group.main(args, prog_name=PROG, standalone_mode=False)
    except (click.exceptions.Abort, KeyboardInterrupt):
        code = 130
    except click.UsageError as exc:
        hint = f" (see '{exc.ctx.command_path} --help')" if exc.ctx is not None else ""
        code = _fail(exc.format_message() + hint, EXIT_USAGE)
    except click.ClickException as exc:
        code = _fail(exc.format_message(), exc.exit_code)
    except OscError as exc:
        if debug:
            traceback.print_exc()
        click.echo(exc.render(), err=True)
        code = 1
    except StoreError as exc:
        if debug:
            traceback.print_exc()
        code = _fail(str(exc), 1)
    except OSError as exc:
        if debug:
            traceback.print_exc()
        code = _fail(f"{exc.strerror or exc}: {exc.filename}" if exc.filename else str(exc), 1)
    except Exception as exc:  # noqa: BLE001 - the last line of defence: one line, traceback with -d
        if debug:
            traceback.print_exc()
        code = _fail(f"internal error: {exc!r} (run with -d for the traceback)", 1)
    sys.exit(code if isinstance(code, int) else 0)


if __name__ == "__main__":
    main()
