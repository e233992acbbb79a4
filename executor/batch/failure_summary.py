"""The end of a batch says which jobs did not pass, why and where, like pytest's "short test summary info".

One line per job that did not pass: its verdict, its testcase name (the variant with its varied
values, as CI pages show it), the reason (the failing action and its location from the job's own
``test.xml``, else the runner's: a timeout, an exit code, no report), and the path of its log. The
reasons are the same texts the merged ``test.xml`` carries, because they come from the same code
(:func:`executor.batch.junit_merge.job_cases`). Names and reasons are printed with control characters
escaped, so a file named with terminal escapes cannot clear or rewrite the screen.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from coverage_engine.results.files import LOG_FILE
from executor.batch.folder_history import latest_jobs_where
from executor.batch.junit_merge import child_cases, job_cases, job_names, variants_of
from executor.output.terminal import printable
from store.jobs import Batch, Job
from store.queue import QueueStore
from store.states import FINAL, JobState

#: Longest reason shown on a summary line (the whole text is in test.xml and the log).
REASON_CHARS = 240
#: At most this many lines are listed; the rest are counted.
MAX_LINES = 50


@dataclass(frozen=True)
class NotPassed:
    """One job that did not pass, as the summary and ``status --list`` show it."""

    status: str
    name: str
    reason: str
    log: str | None
    scenario: str

    def line(self) -> str:
        where = f"  (log: {self.log})" if self.log else ""
        return f"{self.status.upper():<8} {printable(self.name)} - {printable(self.reason)}{where}"

    def as_dict(self) -> dict[str, str | None]:
        return {"status": self.status, "name": self.name, "reason": self.reason, "log": self.log,
                "scenario": self.scenario}


def not_passed(jobs: Iterable[Job], variants: Mapping | None = None) -> list[NotPassed]:
    """The finished jobs that did not pass, in the batch's order."""
    found = []
    for job in jobs:
        if job.status not in FINAL or job.status is JobState.PASSED:
            continue
        names = job_names(job, (variants or {}).get(job.scenario_path))
        cases = job_cases(job, names, child_cases(job))
        problem = next((c for c in cases if c.problem), None)
        reason = (problem.message if problem is not None and problem.message else job.reason) or job.status.value
        reason = " ".join(reason.split())
        if len(reason) > REASON_CHARS:
            reason = reason[:REASON_CHARS - 1] + "…"
        log = os.path.join(job.output_dir, LOG_FILE) if job.output_dir else None
        found.append(NotPassed(job.status.value, names.name, reason, log, job.scenario_path))
    return found


def not_passed_in_store(store: QueueStore, batch_id: int) -> list[NotPassed]:
    """The jobs of a stored batch that did not pass, read with their test.xml (for their reasons)."""
    jobs = [job for job in store.iter_results(batch_id) if job.status is not JobState.PASSED]
    return not_passed(jobs, variants_of(store.engine, [job.scenario_path for job in jobs]))


def not_passed_in_folder(store: QueueStore, batch: Batch, listed: Sequence[Job] | None = None) -> list[NotPassed]:
    """The jobs of the batch's folder whose latest verdict is not a pass: those of the batch, and for a
    rerun or top-up also those of the batches it continues (what the folder's test.xml holds); only
    those are read with their reports. ``listed``: the folder's latest jobs without their results, when
    at hand (:attr:`BatchOutcome.listed <executor.batch.batch_outcome.BatchOutcome.listed>`)."""
    jobs = list(latest_jobs_where(store, batch, lambda job: job.status is not JobState.PASSED, listed))
    return not_passed(jobs, variants_of(store.engine, [job.scenario_path for job in jobs]))


def triage(store: QueueStore, items: list[NotPassed]) -> list[str]:
    """The failures grouped by kind (:mod:`coverage_engine.coverage.triage`), shown when there are several,
    with the varied values each group's variants share; printed before the list of jobs."""
    from coverage_engine.coverage.triage import Failure, group_failures, triage_lines

    if len(items) < 2:
        return []
    infos = variants_of(store.engine, [item.scenario for item in items])
    failures = [Failure(item.name, item.reason, dict(infos[item.scenario].assignment) if item.scenario in infos
                        else {}) for item in items]
    return [printable(line) for line in triage_lines(group_failures(failures))]


def summary_lines(items: list[NotPassed]) -> list[str]:
    """The block printed at the end of a batch (empty when every job passed)."""
    if not items:
        return []
    lines = [f"--- {len(items)} job(s) did not pass ---"]
    lines += [item.line() for item in items[:MAX_LINES]]
    if len(items) > MAX_LINES:
        lines.append(f"... and {len(items) - MAX_LINES} more (scenario_batch_execution status --list failed)")
    return lines
