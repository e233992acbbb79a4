"""The durable job queue: every SQL statement about batches and jobs lives here.

Methods are verbs (``enqueue``, ``claim``, ``finish``, ``heartbeat``, ``reclaim_expired`` …); each
state change is one guarded ``UPDATE`` whose ``WHERE status IN (…)`` comes from :mod:`store.states`
and whose row count is checked, so a late or duplicate result is refused instead of overwriting.

Claiming takes queued rows with ``SELECT … FOR UPDATE SKIP LOCKED`` inside ``UPDATE … RETURNING`` on
PostgreSQL; on SQLite the same statement runs inside ``BEGIN IMMEDIATE`` (see :func:`open_engine`).
A store object keeps one connection and is used from one thread.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from sqlalchemy import Connection, Engine, func, insert, inspect, select
from sqlalchemy.exc import DBAPIError, SQLAlchemyError
from sqlalchemy.sql import ClauseElement

from store import queue_statements as sql
from store import states
from store.database import StoreError, driver_error, ensure_schema, open_engine, open_existing
from store.driver_statements import DriverStatement
from store.jobs import Batch, BatchOptions, Job, JobEnd, JobResult, JobSpec, Reclaimed, WorkerIdentity
from store.queue_reads import QueueReads
from store.queue_tables import QUEUE_TABLES, batches, job_attempts, jobs
from store.states import UNCHARGED_CLAIMS, JobState, Transition

#: Seconds a claim holds a job without a heartbeat.
DEFAULT_LEASE = 60.0

#: Lease expirations after which a job ends as ``error`` instead of being queued again.
DEFAULT_MAX_LOST = 3

#: The columns the record of an attempt is written with (see ``QueueStore._end``).
_ATTEMPT_KEYS = ("job_id", "attempt", "outcome", "exit_code", "started_at", "finished_at", "worker_id", "host",
                 "log_path", "reason")

class LeaseLost(StoreError):
    """The job is no longer held by this worker (its lease expired and was taken over, or it ended)."""


class StoreUnavailable(StoreError):
    """The store could not be reached or was busy; the operation may be retried later."""


class QueueStore(QueueReads):
    """The batch queue in one SQLAlchemy store (SQLite file or PostgreSQL database); reads are inherited."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self._conn: Connection | None = None
        self._driver: dict[object, DriverStatement] = {}    # the per-job statements, compiled once

    def _fast(self, key: object, statement: ClauseElement, column_keys: tuple[str, ...] | None = None) -> DriverStatement:
        """The per-job ``statement`` compiled for this engine's dialect, once per ``key``."""
        compiled = self._driver.get(key)
        if compiled is None:
            compiled = self._driver[key] = DriverStatement(statement, self.engine.dialect, column_keys)
        return compiled

    @classmethod
    def open(cls, url: str | None = None) -> QueueStore:
        """Open the store at ``url`` (``--store``, ``$SCENARIO_STORE`` or the default file) and create tables."""
        engine = open_engine(url)
        ensure_schema(engine, QUEUE_TABLES)
        return cls(engine)

    @classmethod
    def open_existing(cls, url: str | None = None) -> QueueStore:
        """Open a store that must exist already, creating and migrating nothing (for commands that read).

        :class:`~store.database.StoreMissing` when there is no store at ``url``; a store without the
        queue's tables (only variation records, say) is a :class:`StoreError`: it holds no batch.
        """
        engine = open_existing(url)
        try:
            has_batches = inspect(engine).has_table(batches.name)
        except SQLAlchemyError as exc:
            engine.dispose()
            raise StoreError(f"cannot use the store: {driver_error(exc, engine.url.render_as_string(hide_password=True))}"
                             ) from exc
        if not has_batches:
            engine.dispose()
            raise StoreError(f"the store {engine.url.render_as_string(hide_password=True)} holds no batch")
        return cls(engine)

    @property
    def url(self) -> str:
        return self.engine.url.render_as_string(hide_password=True)

    def close(self) -> None:
        """Return the connection and dispose of the engine's pool."""
        self._drop()
        self.engine.dispose()

    def _drop(self) -> None:
        if self._conn is not None:
            try:
                self._conn.close()
            except SQLAlchemyError:
                pass
            self._conn = None

    @contextmanager
    def _tx(self) -> Iterator[Connection]:
        """One transaction on the kept connection; connection trouble becomes :class:`StoreUnavailable`."""
        try:
            if self._conn is None:
                self._conn = self.engine.connect()
            with self._conn.begin():
                yield self._conn
        except DBAPIError as exc:
            self._drop()
            if exc.connection_invalidated or isinstance(exc.orig, (OSError,)) or _is_transient(exc):
                raise StoreUnavailable(f"store {self.url} unavailable: {exc.orig}") from exc
            raise StoreError(driver_error(exc, self.url)) from exc

    # ----------------------------------------------------------------- transitions
    @staticmethod
    def _move(conn: Connection, transition: Transition, target: JobState, where: Sequence,
              values: dict, returning: Sequence = ()) -> Sequence[Any]:
        """Run the one guarded UPDATE of ``transition``; return the rows it changed (ids or ``returning``)."""
        stmt = sql.guarded_update(transition, target, *where).values(**values)
        return conn.execute(stmt.returning(*(returning or [jobs.c.id]))).all()

    @staticmethod
    def _holder(job: Job) -> dict:
        """Bind values of :data:`store.queue_statements.HOLDER` for the attempt ``job`` holds."""
        return {"g_job": job.id, "g_holder": job.worker_id, "g_attempt": job.attempts}

    # ----------------------------------------------------------------- batches
    def create_batch(self, *, mode: str, input_dir: str, output_dir: str, host: str,
                     command: Sequence[str], options: BatchOptions, specs: Sequence[JobSpec]) -> Batch:
        """Create a batch and enqueue one job per spec, in one transaction (all or nothing)."""
        now = time.time()
        with self._tx() as conn:
            batch_id = conn.execute(insert(batches).values(
                created_at=now, mode=mode, input_dir=input_dir, output_dir=output_dir, host=host,
                command=json.dumps(list(command)), options=options.to_json()).returning(batches.c.id)).scalar_one()
            self._enqueue(conn, batch_id, specs, now)
            row = conn.execute(select(batches).where(batches.c.id == batch_id)).mappings().one()
        return Batch.from_row(row)

    def enqueue(self, batch_id: int, specs: Sequence[JobSpec]) -> int:
        """Add jobs to an existing batch; returns how many were added."""
        with self._tx() as conn:
            return self._enqueue(conn, batch_id, specs, time.time())

    @staticmethod
    def _enqueue(conn: Connection, batch_id: int, specs: Sequence[JobSpec], now: float) -> int:
        start = conn.execute(select(func.coalesce(func.max(jobs.c.seq), -1))
                             .where(jobs.c.batch_id == batch_id)).scalar_one() + 1
        rows = [dict(batch_id=batch_id, seq=start + i, name=s.name, scenario_path=s.scenario_path,
                     scenario_sha=s.scenario_sha, scenario_text=s.scenario_text,
                     status=JobState.QUEUED.value, attempts=0, retried=0, lost=0, queued_at=now)
                for i, s in enumerate(specs)]
        if rows:
            conn.execute(insert(jobs), rows)
        return len(rows)

    # ----------------------------------------------------------------- the worker's verbs
    def claim(self, worker: WorkerIdentity, *, limit: int = 1, batch_id: int | None = None,
              shared_only: bool = False, lease: float = DEFAULT_LEASE) -> list[Job]:
        """Take up to ``limit`` queued jobs (lowest batch, then file order) and a lease on each."""
        now = time.time()
        scope = "batch" if batch_id is not None else "shared" if shared_only else "any"
        params = {"b_limit": limit, "b_worker": worker.id, "b_host": worker.host, "b_pid": worker.pid,
                  "b_lease": now + lease, "b_now": now}
        if batch_id is not None:
            params["g_batch"] = batch_id
        statement = self._fast(("claim", scope), sql.claim_statement(scope))
        with self._tx() as conn:
            rows = statement.execute(conn, params).rows
        claimed = [Job.from_row(r) for r in rows]
        claimed.sort(key=lambda j: (j.batch_id, j.seq))
        return claimed

    def started(self, job: Job, child_pid: int, started_at: float | None = None) -> bool:
        """Record the process id of the job's child (its process group), so a dead holder's child can be ended,
        and when the child started (None: the claim's time stands)."""
        statement = self._fast("started", sql.STARTED)
        with self._tx() as conn:
            return statement.execute(conn, {**self._holder(job), "b_child": child_pid,
                                            "b_start": started_at}).rowcount == 1

    def heartbeat(self, worker: WorkerIdentity, lease: float = DEFAULT_LEASE) -> set[int]:
        """Extend the leases of every job ``worker`` runs; returns the ids it still holds."""
        with self._tx() as conn:
            rows = conn.execute(sql.HEARTBEAT, {"g_worker": worker.id, "b_lease": time.time() + lease}).all()
        return {r[0] for r in rows}

    def finish(self, job: Job, result: JobResult) -> None:
        """Record the verdict of the attempt ``job`` holds; :class:`LeaseLost` if it is not ours any more."""
        self._end_one(JobEnd(job, result, Transition.FINISH))

    def retry(self, job: Job, result: JobResult) -> None:
        """Record a failed attempt and queue the job again (infrastructure errors with retries left)."""
        self._end_one(JobEnd(job, result, Transition.RETRY))

    def cancel(self, job: Job, result: JobResult) -> None:
        """Record an attempt stopped by the user; ``--resume`` runs the job again."""
        self._end_one(JobEnd(job, result, Transition.CANCEL))

    def _end_one(self, end: JobEnd) -> None:
        if self.record_ends([end]):
            raise LeaseLost(f"job {end.job.name} (attempt {end.job.attempts}) is no longer held by "
                            f"{end.job.worker_id}")

    def record_ends(self, ends: Sequence[JobEnd]) -> list[JobEnd]:
        """Record the ends of several attempts in one transaction; returns those refused (not held any more).

        One commit for many results: a worker with short jobs records what ended since its last write
        together (a transaction per job cost more than the statements in it). Each end is still its own
        guarded UPDATE; a refused one writes nothing and does not stop the others.
        """
        if not ends:
            return []
        refused: list[JobEnd] = []
        attempt = self._fast("attempt", sql.INSERT_ATTEMPT, _ATTEMPT_KEYS)
        with self._tx() as conn:
            for end in ends:
                job, result = end.job, end.result
                update = self._fast(("end", end.transition), sql.end_statement(end.transition))
                params = {**self._holder(job), "b_status": end.target.value, "b_exit": result.exit_code,
                          "b_end": result.finished_at, "b_start": result.started_at, "b_duration": result.duration,
                          "b_reason": result.reason,
                          "b_xml": result.junit_xml, "b_log": result.log_tail, "b_out": result.output_dir}
                if update.execute(conn, params).rowcount != 1:
                    refused.append(end)
                    continue
                attempt.execute(conn, {
                    "job_id": job.id, "attempt": job.attempts, "outcome": result.status.value,
                    "exit_code": result.exit_code, "started_at": result.started_at,
                    "finished_at": result.finished_at, "worker_id": job.worker_id, "host": job.worker_host,
                    "log_path": result.log_path, "reason": result.reason})
        return refused

    def halt(self, batch_id: int, reason: str = states.HALT_REASON) -> int:
        """Cancel the batch's jobs that have not started (``--halt-on-failure``); returns how many."""
        with self._tx() as conn:
            return len(self._move(conn, Transition.HALT, JobState.CANCELLED, [jobs.c.batch_id == batch_id],
                                  dict(reason=reason)))

    def halt_jobs(self, batch_id: int, names: Sequence[str], reason: str) -> int:
        """Cancel the named jobs of the batch that have not started (``--repeat until-fail`` after a
        failed attempt: that variant's later attempts); returns how many."""
        with self._tx() as conn:
            return len(self._move(conn, Transition.HALT, JobState.CANCELLED,
                                  [jobs.c.batch_id == batch_id, jobs.c.name.in_(list(names))], dict(reason=reason)))

    def resume(self, batch_id: int) -> int:
        """Queue the batch's cancelled jobs again; returns how many."""
        with self._tx() as conn:
            return len(self._move(conn, Transition.RESUME, JobState.QUEUED,
                                  [jobs.c.batch_id == batch_id,
                                   func.coalesce(jobs.c.reason, "") != states.UNTIL_FAIL_REASON],
                                  dict(reason=None)))

    def release(self, worker: WorkerIdentity, job_ids: Iterable[int], *, halted: Iterable[int] = ()) -> int:
        """Give back jobs ``worker`` holds but never started (a claim whose commit reply was lost, a stop,
        a fork server that ended before forking them); returns how many. Those of them in ``halted``
        belong to a batch halted meanwhile (``--halt-on-failure``): they are cancelled in the same
        transaction, as the halt cancelled its other jobs, rather than left queued where nothing claims."""
        ids = sorted(job_ids)
        if not ids:
            return 0
        with self._tx() as conn:
            count = len(self._move(conn, Transition.RECLAIM, JobState.QUEUED,
                                   [jobs.c.worker_id == worker.id, jobs.c.id.in_(ids)],
                                   dict(lease_expires_at=None, reason="released unstarted")))
            halted_ids = sorted(set(halted) & set(ids))
            if halted_ids:
                self._move(conn, Transition.HALT, JobState.CANCELLED, [jobs.c.id.in_(halted_ids)],
                           dict(reason=states.HALT_REASON))
            return count

    def reclaim_expired(self, max_lost: int = DEFAULT_MAX_LOST, now: float | None = None) -> list[Reclaimed]:
        """Take back running jobs whose lease expired: queue them again, or end them as ``error``."""
        now = time.time() if now is None else now
        return self._reclaim([jobs.c.lease_expires_at < now], max_lost, "lease expired")

    def reclaim_worker(self, worker_id: str, reason: str, max_lost: int = DEFAULT_MAX_LOST) -> list[Reclaimed]:
        """Take back the running jobs of a holder known to be dead (e.g. a killed runner on this host)."""
        return self._reclaim([jobs.c.worker_id == worker_id], max_lost, reason)

    def _reclaim(self, where: list, max_lost: int, reason: str) -> list[Reclaimed]:
        """Queue again the jobs ``where`` selects among the running ones.

        A job whose start was recorded (it has a child) lost an attempt: it is charged, and ends as
        ``error`` at the ``max_lost``-th loss. A job its holder took but never started (held for a
        free slot, or waiting at the fork server) goes back as it came, like :meth:`release`: a runner
        killed while it held many jobs would otherwise charge each of them with a run that never
        happened, and three such kills would end a job that never ran as an error. A start is recorded
        :data:`~executor.batch.recorder.STARTED_RECORD_AFTER` after it (a job that ends sooner has its
        result written instead), so a holder lost within that time of a start is not charged either;
        after a job's first :data:`~store.states.UNCHARGED_CLAIMS` claims every loss is.
        """
        cols = [jobs.c.id, jobs.c.attempts, jobs.c.worker_id, jobs.c.worker_host, jobs.c.child_pid,
                jobs.c.lost]
        now = time.time()
        with self._tx() as conn:
            returned = self._move(conn, Transition.RECLAIM, JobState.QUEUED,
                                  [*where, jobs.c.child_pid.is_(None), jobs.c.attempts <= UNCHARGED_CLAIMS],
                                  dict(lease_expires_at=None, reason=f"{reason} before it started"),
                                  returning=cols)
            # (the jobs left running among ``where`` are the ones charged)
            requeued = self._move(conn, Transition.RECLAIM, JobState.QUEUED,
                                  [*where, jobs.c.lost + 1 < max_lost],
                                  dict(lost=jobs.c.lost + 1, lease_expires_at=None, reason=reason),
                                  returning=cols)
            abandoned = self._move(conn, Transition.ABANDON, JobState.ERROR,
                                   [*where, jobs.c.lost + 1 >= max_lost],
                                   dict(lost=jobs.c.lost + 1, lease_expires_at=None, finished_at=now,
                                        reason=f"{reason} {max_lost} times; the job keeps losing its worker"),
                                   returning=cols)
            charged = [*_reclaimed(requeued, JobState.QUEUED), *_reclaimed(abandoned, JobState.ERROR)]
            if charged:
                conn.execute(insert(job_attempts), [
                    dict(job_id=r.job_id, attempt=r.attempt, outcome="lost", finished_at=now,
                         worker_id=r.worker_id, host=r.worker_host, reason=reason) for r in charged])
        return [*charged, *_reclaimed(returned, JobState.QUEUED)]


def _reclaimed(rows: Sequence[Any], status: JobState) -> list[Reclaimed]:
    """The jobs of ``rows`` (returned by ``QueueStore._reclaim``'s moves) taken back, now in ``status``."""
    return [Reclaimed(job_id=r.id, attempt=r.attempts, worker_id=r.worker_id, worker_host=r.worker_host,
                      child_pid=r.child_pid, status=status) for r in rows]


def _is_transient(exc: DBAPIError) -> bool:
    """Errors worth retrying: lost connections, a locked SQLite file, serialization failures."""
    text = str(exc.orig).lower()
    markers = ("database is locked", "could not connect", "connection", "server closed", "terminating",
               "deadlock", "could not serialize", "timeout", "ssl")
    return exc.connection_invalidated or any(m in text for m in markers)

