"""Result recording: the worker's store writes of job starts and ends, several per transaction.

Job threads report :class:`~executor.batch.job_run.Started` and :class:`~executor.batch.job_run.Done`
events; the worker loop hands them here, and :meth:`ResultRecorder.flush` writes what is due:

* a start record (the child's process id, which a later runner needs to end an orphaned child)
  only once the child has run :data:`STARTED_RECORD_AFTER`: a short job's result makes it pointless;
* results once the oldest has waited :data:`RECORD_AFTER`, all of them in one transaction
  (:meth:`store.queue.QueueStore.record_ends`). Measured on 2 cores with trivial jobs at -j 2, one
  transaction per result was the largest share of the batch process's own CPU (its BEGIN and COMMIT
  cost more than the statements in it); a result written 50 ms later costs nothing: until then the
  job is ``running`` in the store, so a runner killed meanwhile leaves it to be run again, as it
  would a job still running.

Written at once, without waiting: everything while the worker stops, every result of a ``-j 1`` run
(its finished lines sit between the children's echoed output) and of a batch that halts on failure
(the halt must come before the next job starts). While the store is unreachable nothing is dropped:
the events stay, in order, until it takes them (see :class:`~executor.batch.claim_pacing.StoreBackoff`).
"""

from __future__ import annotations

import functools
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from executor.batch.claim_pacing import StoreBackoff
from executor.batch.job_run import Attempt, Done, Started
from executor.batch.progress import Reporter
from executor.batch.repeats import later_attempts
from executor.batch.verdict import DISK_FULL_REASON
from store.jobs import Batch, Job, JobEnd, JobResult
from store.queue import QueueStore
from store.states import RETRYABLE, UNTIL_FAIL_REASON, JobState, Transition

if TYPE_CHECKING:
    from store.coverage_records import CoverageRecords

#: Seconds a job's child runs before its process id is written to the store. A short job ends sooner:
#: its result is then written alone. The record serves to end the child of a runner that died together
#: with its watchdog, which matters for long jobs, and it is what makes a lost holder cost the job an
#: attempt (``QueueStore._reclaim``: a job without it goes back uncharged): raising this widens that window.
STARTED_RECORD_AFTER = 0.1

#: Seconds the oldest unwritten result waits for others to share its transaction.
RECORD_AFTER = 0.05

#: Results that make a transaction at once, however recent.
RECORD_BATCH = 64


@dataclass
class WorkerSummary:
    """What a worker did: verdicts it recorded, whether it was stopped, whether there was any work."""

    verdicts: Counter[JobState] = field(default_factory=lambda: Counter())
    interrupted: bool = False
    nothing_to_do: bool = False
    #: The output folder whose disk filled up (the worker stopped there), else None.
    disk_full: str | None = None


@dataclass(frozen=True)
class RecorderHooks:
    """What the recorder tells the worker: stop (a full disk), claim again (a retry), halt a batch's claims."""

    stop: Callable[[], None]
    requeued: Callable[[], None]
    halted: Callable[[int], None]
    stopping: Callable[[], bool]


class ResultRecorder:
    """Holds the worker's unwritten events and writes them when due (see the module doc)."""

    def __init__(self, store: QueueStore, reporter: Reporter, backoff: StoreBackoff, hooks: RecorderHooks,
                 summary: WorkerSummary, *, at_once: bool = False) -> None:
        self.store = store
        self.reporter = reporter
        self.backoff = backoff
        self.hooks = hooks
        self.summary = summary
        self.at_once = at_once                       # write every result without waiting (-j 1)
        self._starts: dict[int, Started] = {}        # job id -> its start, not written yet
        self._results: list[tuple[float, Done]] = []  # (when it came, the result), in that order
        self._to_halt: set[int] = set()
        self._halted: set[int] = set()
        self._coverage: CoverageRecords | None = None

    def __len__(self) -> int:
        return len(self._starts) + len(self._results) + len(self._to_halt)

    def unwritten(self) -> dict[int, Attempt]:
        """The runs whose result waits here, by job id (the worker still holds those jobs in the store)."""
        return {done.run.job.id: done.run for _, done in self._results}

    def halted(self, batch_id: int) -> bool:
        return batch_id in self._halted

    def claimed_from(self, batch_ids: set[int]) -> None:
        """A batch this worker halted and claims from again was resumed (``--resume``, by another
        process): it runs as before its halt, and may halt again."""
        self._halted -= batch_ids

    def add(self, event: Started | Done, now: float) -> None:
        """Keep an event that came at ``now``; a job's result makes its unwritten start record pointless."""
        job_id = event.run.job.id
        if isinstance(event, Started):
            self._starts[job_id] = event
            return
        self._starts.pop(job_id, None)
        self._results.append((now, event))

    def due(self) -> float | None:
        """When the next write is due (``time.monotonic``), None when nothing waits."""
        times = [start.at + STARTED_RECORD_AFTER for start in self._starts.values()]
        if self._results:
            urgent = self.at_once or len(self._results) >= RECORD_BATCH or self._to_halt or any(
                done.run.batch.options.halt_on_failure or done.run.batch.options.until_fail
                for _, done in self._results)
            times.append(self._results[0][0] + (0.0 if urgent else RECORD_AFTER))
        elif self._to_halt:
            times.append(0.0)
        return min(times) if times else None

    def flush(self, now: float, *, force: bool = False) -> None:
        """Write what is due at ``now`` (everything when ``force``); keeps it all while the store is away."""
        due = self.due()
        if due is None or (due > now and not force):
            return
        for start in [s for s in self._starts.values() if force or s.at + STARTED_RECORD_AFTER <= now]:
            if not self._write_start(start):
                return
        if self._results and not self._write_results([done for _, done in self._results]):
            return
        self._results = []
        while self._to_halt:
            batch_id = min(self._to_halt)
            ok, _ = self.backoff.run(functools.partial(self._halt, batch_id))
            if not ok:
                return
            self._to_halt.discard(batch_id)

    def drop(self) -> int:
        """Forget every unwritten event (the store stayed away after a stop); returns how many results."""
        count = len(self._results)
        self._starts.clear()
        self._results.clear()
        self._to_halt.clear()
        return count

    def _write_start(self, start: Started) -> bool:
        if not start.run.lost:
            ok, _ = self.backoff.run(lambda: self.store.started(start.run.job, start.pid, start.began))
            if not ok:
                return False
        del self._starts[start.run.job.id]
        return True

    def _write_results(self, results: list[Done]) -> bool:
        """One transaction for every result; then each is counted, shown, and its coverage kept."""
        for done in results:
            for problem in done.problems:
                self.reporter.warn(f"{done.run.job.name}: {problem}")
            done.problems = []                # said once, even if the write has to be repeated
            if done.result.reason == DISK_FULL_REASON and self.summary.disk_full is None:
                folder = str(done.run.output_dir.parent)
                self.summary.disk_full = folder
                self.reporter.warn(f"no space left on the device holding {folder}: stopping (the jobs "
                                   "under way are stopped; make room, then finish with --resume)")
                self.hooks.stop()
        kept = [done for done in results if not done.run.lost]     # a lost job's result is another's now
        ends = [self._end_of(done) for done in kept]
        ok, refused = self.backoff.run(lambda: self.store.record_ends(ends))
        if not ok:
            return False
        refused_ends = {id(end) for end in refused or ()}      # (one job may end twice: a late attempt)
        for done, end in zip(kept, ends, strict=True):
            if id(end) in refused_ends:
                self.reporter.warn(f"result of {end.job.name} refused: job {end.job.name} (attempt "
                                   f"{end.job.attempts}) is no longer held by {end.job.worker_id}")
            else:
                self._recorded(end, done.run.batch)
        return True

    def _end_of(self, done: Done) -> JobEnd:
        result, job = done.result, done.run.job
        if result.status is JobState.CANCELLED:
            return JobEnd(job, result, Transition.CANCEL)
        if result.status in RETRYABLE and job.retried < done.run.batch.options.retries and not self.hooks.stopping():
            return JobEnd(job, result, Transition.RETRY)
        return JobEnd(job, result, Transition.FINISH)

    def _recorded(self, end: JobEnd, batch: Batch) -> None:
        """What follows a recorded end: a retry wakes the claims, a verdict is counted and may halt the
        batch (``--halt-on-failure``) or the variant's later attempts (``--repeat until-fail:N``)."""
        job, result = end.job, end.result
        if end.transition is Transition.RETRY:
            self.hooks.requeued()
        elif end.transition is Transition.FINISH:
            self._record_coverage(job, result)
            self.summary.verdicts[result.status] += 1
            if result.status is not JobState.PASSED and batch.options.halt_on_failure:
                self._to_halt.add(job.batch_id)
            if result.status is not JobState.PASSED and batch.options.until_fail:
                later = later_attempts(job.name, batch.options.repeat)
                self.backoff.run(lambda: self.store.halt_jobs(job.batch_id, later, UNTIL_FAIL_REASON))
        self.reporter.job_finished(job, result, retrying=end.transition is Transition.RETRY)

    def _record_coverage(self, job: Job, result: JobResult) -> None:
        """Keep the job's ``coverage.json`` (read on this host with its result) in the store, for reports
        from any host; a file that does not validate is said and left out (the job's verdict stands)."""
        if not result.coverage_json:
            return
        from coverage_engine.coverage.errors import RunFileError
        from coverage_engine.coverage.run_file import parse_run_coverage, run_coverage_dict
        from store.coverage_records import CoverageRecords

        try:
            if self._coverage is None:
                self._coverage = CoverageRecords.attach(self.store.engine)
            run = parse_run_coverage(result.coverage_json)
            self._coverage.record(job.id, job.attempts, run_coverage_dict(run))
        except RunFileError as exc:
            self.reporter.warn(f"{job.name}: coverage.json not kept: {exc.render()}")

    def _halt(self, batch_id: int) -> None:
        if batch_id not in self._halted:
            count = self.store.halt(batch_id)
            self._halted.add(batch_id)
            self.hooks.halted(batch_id)
            if count:
                self.reporter.warn(f"halting: {count} job(s) not started (--halt-on-failure)")
