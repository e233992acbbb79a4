"""Read-only questions about the queue: batches, counts per state, running jobs, results for reports.

A mixin of :class:`store.queue.QueueStore`, kept apart so the module with the state changes stays small.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import AbstractContextManager
from typing import Any

from sqlalchemy import Connection, Select, func, select

from store.database import StoreError
from store.jobs import Batch, Job
from store.queue_statements import JOB_COLUMNS, in_shared_batches
from store.queue_tables import batches, job_attempts, jobs
from store.states import FINAL, JobState

#: Columns of a job with its result (for reports); the scenario text is read only by workers that need it.
_RESULT_COLUMNS = [c for c in jobs.c if c.name != "scenario_text"]


class QueueReads:
    """Reads over batches and jobs; needs ``_tx()`` from the class it is mixed into."""

    def _tx(self) -> AbstractContextManager[Connection]:  # pragma: no cover - provided by QueueStore
        raise NotImplementedError

    def batch(self, batch_id: int) -> Batch:
        """The batch with this id; :class:`StoreError` if there is none."""
        with self._tx() as conn:
            row = conn.execute(select(batches).where(batches.c.id == batch_id)).mappings().first()
        if row is None:
            raise StoreError(f"there is no batch {batch_id} in the store")
        return Batch.from_row(row)

    def latest_batch(self, *, output_dir: str | None = None, mode: str | None = None) -> Batch | None:
        """The newest batch, optionally only for one output folder or one mode."""
        stmt = select(batches).order_by(batches.c.id.desc()).limit(1)
        if output_dir is not None:
            stmt = stmt.where(batches.c.output_dir == output_dir)
        if mode is not None:
            stmt = stmt.where(batches.c.mode == mode)
        with self._tx() as conn:
            row = conn.execute(stmt).mappings().first()
        return None if row is None else Batch.from_row(row)

    def counts(self, batch_id: int | None = None, *, shared_only: bool = False) -> dict[JobState, int]:
        """Number of jobs in each state (every state present, zero when empty)."""
        stmt = select(jobs.c.status, func.count()).group_by(jobs.c.status)
        stmt = self._scope(stmt, batch_id, shared_only)
        with self._tx() as conn:
            found: dict[str, int] = {status: count for status, count in conn.execute(stmt)}
        return {state: int(found.get(state.value, 0)) for state in JobState}

    def jobs(self, batch_id: int, *, results: bool = False) -> list[Job]:
        """The jobs of a batch in file order; with ``results`` also their JUnit XML and log tails."""
        cols = _RESULT_COLUMNS if results else JOB_COLUMNS
        stmt = select(*cols).where(jobs.c.batch_id == batch_id).order_by(jobs.c.seq)
        with self._tx() as conn:
            return [Job.from_row(r) for r in conn.execute(stmt).mappings()]

    def iter_results(self, batch_id: int, chunk: int = 500) -> Iterator[Job]:
        """The jobs of a batch with their results, read in chunks so a big batch never sits in memory."""
        last = -1
        while True:
            stmt = (select(*_RESULT_COLUMNS)
                    .where(jobs.c.batch_id == batch_id, jobs.c.seq > last).order_by(jobs.c.seq).limit(chunk))
            with self._tx() as conn:
                rows = [Job.from_row(r) for r in conn.execute(stmt).mappings()]
            yield from rows
            if len(rows) < chunk:
                return
            last = rows[-1].seq

    def results_by_id(self, job_ids: Sequence[int]) -> list[Job]:
        """The jobs with these ids (a few hundred at a time), with their results, in the order of ``job_ids``."""
        stmt = select(*_RESULT_COLUMNS).where(jobs.c.id.in_(list(job_ids)))
        with self._tx() as conn:
            found = {job.id: job for job in (Job.from_row(r) for r in conn.execute(stmt).mappings())}
        return [found[job_id] for job_id in job_ids if job_id in found]

    def running(self, batch_id: int | None = None, *, shared_only: bool = False) -> list[Job]:
        """Jobs currently held by a worker."""
        stmt = (select(*JOB_COLUMNS).where(jobs.c.status == JobState.RUNNING.value)
                .order_by(jobs.c.batch_id, jobs.c.seq))
        stmt = self._scope(stmt, batch_id, shared_only)
        with self._tx() as conn:
            return [Job.from_row(r) for r in conn.execute(stmt).mappings()]

    def attempts(self, job_id: int) -> list[dict[str, Any]]:
        """Every recorded attempt of a job, oldest first."""
        stmt = select(job_attempts).where(job_attempts.c.job_id == job_id).order_by(job_attempts.c.attempt)
        with self._tx() as conn:
            return [dict(r) for r in conn.execute(stmt).mappings()]

    def scenario_text(self, job_id: int) -> str | None:
        """The scenario file's content as it was when enqueued (for workers that do not share the files)."""
        with self._tx() as conn:
            return conn.execute(select(jobs.c.scenario_text).where(jobs.c.id == job_id)).scalar()

    def recent_pace(self, batch_id: int, last: int) -> tuple[int, float | None]:
        """The batch's latest ``last`` verdicts: how many there are, and the seconds from the earliest
        start to the latest end among them (None when there is none), by the workers' own clocks: its
        recent throughput, for an ETA."""
        latest = (select(jobs.c.started_at, jobs.c.finished_at)
                  .where(jobs.c.batch_id == batch_id, jobs.c.finished_at.is_not(None),
                         jobs.c.status.in_([state.value for state in FINAL]))
                  .order_by(jobs.c.finished_at.desc()).limit(last).subquery())
        stmt = select(func.count(), func.min(latest.c.started_at), func.max(latest.c.finished_at))
        with self._tx() as conn:
            count, first, end = conn.execute(stmt).one()
        return int(count), None if first is None or end is None else float(end) - float(first)

    @staticmethod
    def _scope(stmt: Select[Any], batch_id: int | None, shared_only: bool) -> Select[Any]:
        """``stmt`` limited to one batch's jobs, or to the shared batches' jobs, or as it is."""
        if batch_id is not None:
            return stmt.where(jobs.c.batch_id == batch_id)
        if shared_only:
            return stmt.where(in_shared_batches())
        return stmt
