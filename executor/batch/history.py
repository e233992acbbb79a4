"""Batches of one store over time: the figures kept per batch, the trend read back, a batch as a diff side.

At the end of a batch's report its figures (runs, pass rate, variants, flaky, overall grade, holes) are
kept in the store (:mod:`store.batch_summaries`) and the store's recent batches are written beside
the report as ``history.json`` (so a results folder carries its trend to any host, and to the HTML
report). ``scenario_coverage history`` reads the kept rows with one query for the counts; a batch
without kept figures (an older store, a shared batch nobody reported) has its grade computed when
asked for, the store left unchanged.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import replace

from coverage_engine.coverage.diff import Side, VariantOutcome
from coverage_engine.coverage.errors import CoverageError
from coverage_engine.coverage.grading import build_report
from coverage_engine.coverage.model import CoverageReport
from coverage_engine.coverage.trend import HISTORY_FILE, KEPT_BATCHES, TrendPoint, history_document
from coverage_engine.results.atomic import write_text_atomically
from coverage_engine.results.verdicts import VERDICT_OF_STATE
from executor.batch.batch_outcome import BatchOutcome
from executor.batch.coverage_source import batch_source
from executor.batch.flaky import flaky_variants
from executor.batch.repeats import attempt_reason, group_attempts
from store.batch_summaries import BatchSummary, read_summaries, record_summary
from store.coverage_records import CoverageRecords
from store.database import StoreError
from store.jobs import Batch
from store.outcome_history import batch_counts, ran_before, variant_keys
from store.queue import QueueStore
from store.states import FINAL, JobState


def batch_report(store: QueueStore, batch: Batch) -> CoverageReport:
    """The coverage report of a stored batch, read through the store's own engine."""
    return build_report(batch_source(CoverageRecords(store.engine), batch, own=False))


def _grade_and_holes(store: QueueStore, batch: Batch) -> tuple[float | None, int | None]:
    try:
        report = batch_report(store, batch)
    except (CoverageError, StoreError):
        return None, None
    return report.grade, report.holes_count() if report.grade is not None else None


def record_batch_summary(store: QueueStore, batch: Batch, outcome: BatchOutcome) -> None:
    """Keep the batch's figures in the store and write ``history.json`` beside its report. A history that
    cannot be written is left out: the batch's own results are already safe."""
    grade, holes = _grade_and_holes(store, batch)
    variants = sum(outcome.counts.values())
    summary = BatchSummary(batch.id, outcome.runs, outcome.runs_passed, variants, outcome.counts[JobState.PASSED],
                           len(outcome.flaky), grade, holes)
    try:
        record_summary(store.engine, summary)
        points = history_points(store, last=KEPT_BATCHES)
        text = json.dumps(history_document(points, batch.id), indent=1) + "\n"
        write_text_atomically(os.path.join(batch.output_dir, HISTORY_FILE), text)
    except (OSError, StoreError):
        pass


def history_points(store: QueueStore, *, last: int | None = None,
                   known: Mapping[int, tuple[float | None, int]] | None = None) -> list[TrendPoint]:
    """The store's batches, oldest first (the ``last`` ones), with their kept figures, those ``known``
    (batch id: grade and holes, already computed by the caller), or computed ones."""
    known = known or {}
    rows = batch_counts(store.engine, last=last)
    kept = read_summaries(store.engine, [row.batch_id for row in rows])
    points = []
    for row in rows:
        point = TrendPoint(row.batch_id, row.created_at, row.finished, row.passed, row.jobs, 0,
                           output_dir=row.output_dir)
        summary = kept.get(row.batch_id)
        if summary is not None:
            point = replace(point, variants=summary.variants, variants_passed=summary.variants_passed,
                            flaky=summary.flaky, grade=summary.grade, holes=summary.holes)
        elif row.batch_id in known:
            point = replace(point, grade=known[row.batch_id][0], holes=known[row.batch_id][1])
        elif row.finished:
            grade, holes = _grade_and_holes(store, store.batch(row.batch_id))
            point = replace(point, grade=grade, holes=holes)
        points.append(point)
    return points


def store_side(store: QueueStore, batch: Batch) -> Side:
    """A stored batch as one side of ``scenario_coverage diff``: its variants' verdicts and its coverage."""
    jobs = list(store.iter_results(batch.id))
    flaky = flaky_variants(store, jobs, batch.id)
    outcomes: dict[str, VariantOutcome] = {}
    if batch.options.repeat > 1:
        for group in group_attempts(jobs, batch.options.pass_rate, flaky):
            job = group.as_job()
            first = next((j for j in group.ran if j.status is not JobState.PASSED), None)
            reason = None if job.status is JobState.PASSED else attempt_reason(first or job)
            outcomes[group.variant] = VariantOutcome(group.variant, VERDICT_OF_STATE[job.status.value],
                                                     reason, group.flaky)
    else:
        for job in jobs:
            verdict = VERDICT_OF_STATE[job.status.value]
            reason = attempt_reason(job) if job.status in FINAL else None
            outcomes[job.name] = VariantOutcome(job.name, verdict, reason, job.name in flaky)
    return Side(f"batch {batch.id} ({batch.output_dir})", outcomes, batch_report(store, batch))


def store_extras(url: str | None, results: str | None, batch_id: int | None, *, trend: bool = True,
                 graded: tuple[float | None, int] | None = None) -> dict[str, object]:
    """What the reports show beyond the batch, for a stored batch: the store's batches (``history``, up to
    :data:`KEPT_BATCHES`; only with ``trend``), the batch's id (``current``) and its flaky variants.
    ``graded``: the grade and holes of the report being made (of this batch: not computed a second time)."""
    from executor.batch.coverage_source import pick_batch
    from executor.batch.flaky import keyed_records

    store = QueueStore.open_existing(url)
    try:
        batch = pick_batch(store, results, batch_id)
        known = {batch.id: graded} if graded is not None else {}
        points = [p for p in history_points(store, last=KEPT_BATCHES, known=known) if p.batch <= batch.id] \
            if trend else []
        kept = read_summaries(store.engine, [batch.id]).get(batch.id)
        # A batch whose kept figures count no flaky variant needs no look at the store's other batches.
        none = (kept is not None and kept.flaky == 0) or (batch.options.repeat <= 1 and not ran_before(store.engine,
                                                                                                      batch.id))
        records = {} if none else keyed_records(store, variant_keys(store.engine, batch.id), batch.id)
    finally:
        store.close()
    flaky = [(name, record.text()) for name, record in records.items() if record.flaky]
    return {"history": tuple(points), "current": batch.id, "flaky": tuple(flaky)}
