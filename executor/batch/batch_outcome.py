"""A batch as its report counts it: one verdict per variant, the flaky ones named.

Without ``--repeat`` a job is a variant, and the jobs are streamed to the report as before (100,000
jobs never sit in memory with their reports); only the flaky ones get a note. With ``--repeat`` the
attempts of each variant are combined (:mod:`executor.batch.repeats`) and the counts, the exit code
and the merged report are per variant.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from executor.batch import folder_history
from executor.batch.flaky import flaky_variants
from executor.batch.junit_merge import JobNotes
from executor.batch.repeats import VariantRepeats, group_attempts, variant_counts
from store.jobs import Batch, Job
from store.queue import QueueStore
from store.states import JobState

#: The JUnit property (on the job's testsuite) that names a flaky variant.
FLAKY_PROPERTY = "flaky"


@dataclass(frozen=True)
class BatchOutcome:
    """What the merged report of a batch is built from, and the per-variant counts it comes to."""

    jobs: Iterable[Job]                   # one per variant; a stream when the batch has no repeats
    counts: dict[JobState, int]           # variants per state
    #: The folder's latest job of each name, without their reports (what the report lists, light).
    listed: tuple[Job, ...] = ()
    notes: dict[str, JobNotes] = field(default_factory=dict)
    flaky: tuple[str, ...] = ()
    groups: tuple[VariantRepeats, ...] = ()   # the repeated variants (empty without --repeat)
    #: Jobs (attempts) run and passed: the run pass rate.
    runs: int = 0
    runs_passed: int = 0


def batch_outcome(store: QueueStore, batch: Batch) -> BatchOutcome:
    """The batch's variants with their verdicts and notes (see the module doc). A batch that continues
    earlier ones (``--rerun-failed``, ``--only-new``) stands for the folder: the latest job of each name
    over the batches it continues (:mod:`executor.batch.folder_history`)."""
    listed = tuple(folder_history.latest_jobs(store, batch, results=False))
    flaky = flaky_variants(store, listed, batch.id)
    job_counts = folder_history.counts_of(listed)
    finished = sum(job_counts[s] for s in (JobState.PASSED, JobState.FAILED, JobState.ERROR, JobState.TIMEOUT))
    if batch.options.repeat <= 1:
        names = tuple(job.name for job in listed if job.name in flaky)
        notes = {name: JobNotes({FLAKY_PROPERTY: "true"}) for name in names}
        return BatchOutcome(folder_history.latest_jobs(store, batch), job_counts, listed, notes, names,
                            runs=finished, runs_passed=job_counts[JobState.PASSED])
    groups = group_attempts(folder_history.latest_jobs(store, batch), batch.options.pass_rate, flaky)
    notes = {group.variant: JobNotes(group.properties(), group.attempts_text()) for group in groups}
    return BatchOutcome([group.as_job() for group in groups], variant_counts(groups), listed, notes,
                        tuple(group.variant for group in groups if group.flaky), tuple(groups),
                        runs=finished, runs_passed=job_counts[JobState.PASSED])


def flaky_lines(outcome: BatchOutcome, limit: int = 50) -> list[str]:
    """The block naming the flaky variants at the end of a batch (empty when there is none)."""
    if not outcome.flaky:
        return []
    by_name = {group.variant: group for group in outcome.groups}
    lines = [f"--- {len(outcome.flaky)} flaky variant(s): passed and failed (this batch or earlier ones) ---"]
    for name in outcome.flaky[:limit]:
        group = by_name.get(name)
        detail = f" - {group.summary()}" if group is not None else " - passed and failed in this store's batches"
        lines.append(f"FLAKY    {name}{detail}")
    if len(outcome.flaky) > limit:
        lines.append(f"... and {len(outcome.flaky) - limit} more (scenario_batch_execution status --list flaky)")
    return lines
