"""``scenario_coverage history`` and ``scenario_coverage diff``: batches over time, and two batches compared.

    scenario_coverage history [--store URL] [--last N] [--json]
    scenario_coverage diff A B [--store URL] [--json]

Thin click commands over :mod:`executor.batch.history` (the store's batches and their kept figures) and
:mod:`coverage_engine.coverage.diff` / :mod:`coverage_engine.coverage.trend` (the comparison and the
rows). ``A`` and ``B`` are results folders, or batch ids of the store. ``diff`` exits 1 when B has a
new failure (a variant that passed in A and fails in B, or a new variant that fails), for CI gating.
The store is only read.
"""

from __future__ import annotations

import json
import os
import sys
from typing import TYPE_CHECKING

import click

from cli.options import debug_option, store_option

if TYPE_CHECKING:
    from coverage_engine.coverage.diff import Side
    from coverage_engine.coverage.model import CoverageReport

CONTEXT = {"help_option_names": ["-h", "--help"]}

#: ``diff``'s exit code when B has a new failure.
EXIT_NEW_FAILURE = 1


@click.command(context_settings=CONTEXT)
@store_option
@click.option("--last", type=click.IntRange(min=1), metavar="N", help="Only the newest N batches.")
@click.option("--json", "as_json", is_flag=True, help="Print the rows as JSON (format scenario-coverage/history).")
@debug_option
def history_command(store_url: str | None, last: int | None, as_json: bool, debug: bool) -> int:
    """Show the store's batches over time: runs, pass rate, variants, flaky, overall grade and holes (the
    newest batch marked *)."""
    from coverage_engine.coverage.trend import history_document, history_lines
    from executor.batch.history import history_points
    from store.queue import QueueStore

    store = QueueStore.open_existing(store_url)
    try:
        points = history_points(store, last=last)
    finally:
        store.close()
    current = points[-1].batch if points else None
    if as_json:
        click.echo(json.dumps(history_document(points, current), indent=2))
    else:
        for line in history_lines(points, current):
            click.echo(line)
    return 0


def _side(given: str, store_url: str | None, named: bool) -> Side:
    """A results folder, or (digits that name no folder) a batch id of the store."""
    from coverage_engine.coverage.diff import Side, folder_outcomes
    from coverage_engine.coverage.errors import ResultsError
    from coverage_engine.coverage.grading import build_report
    from coverage_engine.coverage.results_folder import read_results_folder
    from coverage_engine.location import Location
    from coverage_engine.results.read import JunitUnreadable

    if os.path.isdir(given) and not named:
        try:
            outcomes = folder_outcomes(given)
        except JunitUnreadable as exc:
            raise ResultsError(str(exc), Location.whole_file(given)) from None
        return Side(given, outcomes, build_report(read_results_folder(given)))
    if not given.isdigit():
        if os.path.isdir(given):
            raise click.UsageError(f"{given}: with --store, A and B are batch ids")
        raise ResultsError("no such results folder (and not a batch id)", Location.whole_file(given))
    from executor.batch.history import store_side
    from store.queue import QueueStore

    store = QueueStore.open_existing(store_url)
    try:
        return store_side(store, store.batch(int(given)))
    finally:
        store.close()


@click.command(context_settings=CONTEXT)
@click.argument("a")
@click.argument("b")
@store_option
@click.option("--json", "as_json", is_flag=True, help="Print the comparison as JSON (format scenario-coverage/diff).")
@debug_option
def diff_command(a: str, b: str, store_url: str | None, as_json: bool, debug: bool) -> int:
    """Compare batch A with batch B (results folders, or batch ids of the store): regressions (passed in A,
    fail in B), fixed, new, gone and flaky variants, and per coverage item the buckets gained and lost.
    Exit 1 when B has a new failure."""
    from coverage_engine.coverage.diff import compare, diff_document, diff_lines
    from executor.output.terminal import printable

    named = click.get_current_context().get_parameter_source("store_url") is click.core.ParameterSource.COMMANDLINE
    result = compare(_side(a, store_url, named), _side(b, store_url, named))
    if as_json:
        sys.stdout.write(json.dumps(diff_document(result), indent=2) + "\n")
    else:
        for line in diff_lines(result):
            click.echo(printable(line))
    return EXIT_NEW_FAILURE if result.new_failures else 0


def with_history(report: CoverageReport, results: tuple[str, ...], store_url: str | None,
                 batch_id: int | None, *, trend: bool = True) -> CoverageReport:
    """``report`` with what the HTML shows beyond its batch (``report.extra``: history, current, flaky):
    from the store when it is read (``store_url`` given), else from the one results folder's
    ``history.json`` and merged ``test.xml``; several folders have no one trend. Without ``trend`` only the
    flaky variants (the text and JSON reports)."""
    import dataclasses

    if store_url is not None or not results:
        from executor.batch.history import store_extras

        extra = store_extras(store_url, results[0] if results else None, batch_id, trend=trend,
                             graded=(report.grade, report.holes_count()))
    elif len(results) == 1 and os.path.isdir(results[0]):
        from coverage_engine.coverage.diff import folder_outcomes
        from coverage_engine.coverage.trend import read_history_file
        from coverage_engine.results.read import JunitUnreadable

        points, current = read_history_file(results[0])
        try:
            outcomes = folder_outcomes(results[0])
        except JunitUnreadable:
            outcomes = {}
        flaky = tuple((o.name, o.detail or "passed and failed in the store's batches")
                      for o in outcomes.values() if o.flaky)
        extra = {"history": tuple(points), "current": current, "flaky": flaky}
    else:
        return report
    return dataclasses.replace(report, extra={**report.extra, **extra})
