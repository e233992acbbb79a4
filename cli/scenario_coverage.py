"""``scenario_coverage``: report the coverage of a batch (or of one run) in the terminal, as JSON or as HTML.

    scenario_coverage report [RESULTS...] [--store URL] [--batch ID] [--plan F] [-o FILE] [--fail-under PCT]
    scenario_coverage html   [RESULTS...] [...] [-o coverage.html]
    scenario_coverage json   [RESULTS...] [...] [-o FILE]

Thin click commands: the reading, merging and grading is :mod:`coverage_engine.coverage` (and
:mod:`executor.batch.coverage_source` for a store); here options are parsed, and :mod:`cli.boundary` turns
errors into messages and exit codes. Where the runs come from: ``RESULTS`` (results folders, a folder
of shards' results folders, or one run's folder; several are merged) unless ``--store`` is on the command line; with ``--store``, or without ``RESULTS``, the
store (``--store``, ``$SCENARIO_STORE`` or the default file), which is only read: a store that is not
there is an error and nothing is created or upgraded.

Exit codes: 0 · 1 the grade is below ``--fail-under``, or the results, plan or store cannot be used ·
2 usage error (the command line itself, or no store where one was named) · 130 interrupted.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import click

from cli.boundary import Boundary
from cli.coverage_history import diff_command, history_command, with_history
from cli.options import debug_option, store_option
from coverage_engine.printable import printable
from store.database import StoreMissing

if TYPE_CHECKING:
    from coverage_engine.coverage.model import CoverageReport

PROG = "scenario_coverage"
EXIT_BELOW = 1
CONTEXT = {"help_option_names": ["-h", "--help"]}

F = TypeVar("F", bound=Callable[..., Any])


def _common(func: F) -> F:
    """The options every subcommand has, in the order ``--help`` lists them."""
    func = debug_option(func)
    func = click.option("--fail-under", type=click.FloatRange(0, 100), metavar="PCT",
                        help="Exit 1 when the overall grade is below PCT percent.")(func)
    func = click.option("--plan", "plan_file", type=click.Path(dir_okay=False), metavar="FILE",
                        help="YAML plan: item weights and per-bucket hit targets (at_least).")(func)
    func = click.option("--batch", "batch_id", type=click.IntRange(min=1), metavar="ID",
                        help="The batch of the store (default: the latest batch of RESULTS, or the latest "
                             "batch).")(func)
    func = store_option(func)
    return click.argument("results", nargs=-1, type=click.Path(file_okay=True))(func)


def _store_named() -> bool:
    """Whether ``--store`` is on the command line (``$SCENARIO_STORE`` alone does not replace RESULTS)."""
    source = click.get_current_context().get_parameter_source("store_url")
    return source is click.core.ParameterSource.COMMANDLINE


def _report(folders: tuple[str, ...], store_url: str | None, batch_id: int | None,
            plan_file: str | None) -> CoverageReport:
    from coverage_engine.coverage.grading import build_report
    from coverage_engine.coverage.plan import read_plan

    named = _store_named()
    if folders and not named and batch_id is not None:
        raise click.UsageError("--batch needs --store")
    if len(folders) > 1 and named:
        raise click.UsageError("--store reads one batch: give at most one RESULTS folder with it")
    plan = read_plan(plan_file) if plan_file else None
    if folders and not named:
        from coverage_engine.coverage.results_folder import read_results_folders

        return build_report(read_results_folders(list(folders)), plan)
    from executor.batch.coverage_source import store_source

    results = folders[0] if folders else None
    try:
        source = store_source(store_url, results, batch_id)
    except StoreMissing as exc:
        if named:
            raise
        raise click.UsageError(f"missing RESULTS (a results folder or a run's output folder), and {exc}; "
                               f"give RESULTS or --store URL") from exc
    return build_report(source, plan)


def _history_store(results: tuple[str, ...], store_url: str | None) -> str | None:
    """The store the report's history and flaky variants come from: the one read (``--store``, or no
    RESULTS), else None (the results folder's own files)."""
    return store_url if _store_named() or not results else None


def _gate(report: CoverageReport, fail_under: float | None) -> int:
    """``--fail-under``: one comparison on the grade as the report shows it (one decimal), as coverage.py
    compares at its display precision: a report saying 90.0 % never fails ``--fail-under 90``."""
    if fail_under is None:
        return 0
    grade = round(report.grade, 1) if report.grade is not None else 0.0
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
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write the (plain) report to FILE ('-': standard output).")
def report_command(results: tuple[str, ...], store_url: str | None, batch_id: int | None, plan_file: str | None,
                   fail_under: float | None, debug: bool, output: str | None) -> int:
    """Print the coverage of RESULTS (one or more results folders, merged): items, buckets, grades, holes and
    failing runs."""
    from rich.console import Console

    from coverage_engine.coverage.render_text import plain_width, render_text
    from executor.output.terminal import wants_rich

    report = _report(results, store_url, batch_id, plan_file)
    report = with_history(report, results, _history_store(results, store_url), batch_id, trend=False)
    rich = not output and wants_rich(sys.stdout)   # the one terminal policy; rich itself honours NO_COLOR
    if rich:
        render_text(report, Console(force_terminal=True, highlight=False, markup=False), plain=False)
        return _gate(report, fail_under)
    import io

    buffer = io.StringIO()
    console = Console(file=buffer, width=plain_width(report), color_system=None, force_terminal=False,
                      markup=False)
    render_text(report, console, plain=True)
    text = "".join(line.rstrip() + "\n" for line in buffer.getvalue().splitlines())   # no padding in files and logs
    if output:
        from coverage_engine.results.atomic import write_output

        write_output(_output_path(output), text)
    else:
        sys.stdout.write(text)
    return _gate(report, fail_under)


@click.command(context_settings=CONTEXT)
@_common
@click.option("-o", "--output", type=click.Path(dir_okay=False), default="coverage.html", show_default=True,
              help="The HTML file to write (one self-contained file; '-': standard output).")
def html_command(results: tuple[str, ...], store_url: str | None, batch_id: int | None, plan_file: str | None,
                 fail_under: float | None, debug: bool, output: str) -> int:
    """Write the coverage of RESULTS as one self-contained HTML page (no network needed to view it)."""
    from coverage_engine.coverage.render_html import render_html
    from coverage_engine.results.atomic import STDOUT, write_output

    path = _output_path(output)
    report = _report(results, store_url, batch_id, plan_file)
    report = with_history(report, results, _history_store(results, store_url), batch_id)
    folder = os.getcwd() if path == STDOUT else os.path.dirname(os.path.abspath(path))
    text = render_html(report, output_dir=folder, generated=time.strftime("%Y-%m-%d %H:%M"))
    write_output(path, text)
    if path == STDOUT:
        return _gate(report, fail_under)
    grade = "no graded item" if report.grade is None else f"grade {report.grade:.1f} %"
    click.echo(printable(f"wrote {path} ({grade}, {len(report.runs)} run(s))"))
    return _gate(report, fail_under)


@click.command(context_settings=CONTEXT)
@_common
@click.option("-o", "--output", type=click.Path(dir_okay=False), default="-", show_default=True,
              help="The JSON file to write ('-': standard output).")
def json_command(results: tuple[str, ...], store_url: str | None, batch_id: int | None, plan_file: str | None,
                 fail_under: float | None, debug: bool, output: str) -> int:
    """Write the coverage of RESULTS as JSON (format scenario-coverage/report, see docs/coverage.md)."""
    from coverage_engine.coverage.render_json import render_json
    from coverage_engine.results.atomic import write_output

    report = _report(results, store_url, batch_id, plan_file)
    text = render_json(with_history(report, results, _history_store(results, store_url), batch_id, trend=False))
    write_output(_output_path(output), text)
    return _gate(report, fail_under)


@click.version_option(package_name="scenario-coverage", message="%(prog)s %(version)s")
@click.group(context_settings=CONTEXT,
             commands={"report": report_command, "html": html_command, "json": json_command,
                       "history": history_command, "diff": diff_command})
def group() -> None:
    """Report the coverage of a batch's results folder (or of one run's folder, or of a batch in the store)."""


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point; errors become messages and exit codes in :mod:`cli.boundary`."""
    Boundary(PROG, quick_end=True).main(group, argv)     # (it reads results: it runs no scenario)


if __name__ == "__main__":  # pragma: no cover
    main()
