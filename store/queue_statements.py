"""The queue's statements, built once: every state change is an UPDATE guarded by the state machine.

Building a SQLAlchemy statement costs far more than running a cached one, and a worker runs the
same few statements thousands of times, so the hot ones are built here once with bind parameters
(named ``b_*`` for values and ``g_*`` for guards; SQLAlchemy reserves column names for SET values).
"""

from __future__ import annotations

import functools
from typing import Any

from sqlalchemy import ColumnElement, Update, and_, bindparam, func, insert, select, update

from store import states
from store.queue_tables import batches, job_attempts, jobs
from store.states import JobState, Transition

#: Columns handed out with a job; the large result columns are read only for reports.
JOB_COLUMNS = [c for c in jobs.c if c.name not in ("junit_xml", "log_tail", "scenario_text")]



def in_shared_batches() -> ColumnElement[bool]:
    """``jobs.batch_id`` is one of a shared batch (what ``worker`` runs when not limited to one batch)."""
    return jobs.c.batch_id.in_(select(batches.c.id).where(batches.c.mode == "shared"))


#: A result counts only from the lease holder of this very attempt (``attempts`` is the fencing token).
HOLDER = and_(jobs.c.id == bindparam("g_job"), jobs.c.worker_id == bindparam("g_holder"),
              jobs.c.attempts == bindparam("g_attempt"))

INSERT_ATTEMPT = insert(job_attempts)

#: The child's process id, and when it started (a job claimed in a chunk starts later than its claim).
STARTED = (update(jobs).where(jobs.c.status == JobState.RUNNING.value, HOLDER)
           .values(child_pid=bindparam("b_child"), started_at=func.coalesce(bindparam("b_start"), jobs.c.started_at)))

HEARTBEAT = (update(jobs)
             .where(jobs.c.worker_id == bindparam("g_worker"), jobs.c.status == JobState.RUNNING.value)
             .values(lease_expires_at=bindparam("b_lease")).returning(jobs.c.id))


def source_clause(transition: Transition) -> ColumnElement[bool]:
    """``status = 'x'`` (or ``status IN (…)``) for the states ``transition`` may start from."""
    names = sorted(s.value for s in states.sources(transition))
    return jobs.c.status == names[0] if len(names) == 1 else jobs.c.status.in_(names)


def guarded_update(transition: Transition, target: JobState, *where: ColumnElement[bool]) -> Update:
    """The UPDATE of one transition to ``target``, limited to rows in its source states and ``where``."""
    states.check(transition, target)
    return update(jobs).where(source_clause(transition), *where).values(status=target.value)


@functools.cache
def claim_statement(scope: str) -> Update:
    """Claim up to ``b_limit`` queued jobs: of batch ``g_batch`` (scope "batch"), of shared batches, or any.

    The rows are picked in a CTE with ``FOR UPDATE SKIP LOCKED`` (PostgreSQL; SQLite runs the same
    statement inside BEGIN IMMEDIATE). Not "id IN (subquery)": PostgreSQL may rescan such a subquery
    per row and lock more rows than the limit; a CTE with FOR UPDATE is evaluated once.
    """
    pick = select(jobs.c.id).where(jobs.c.status == JobState.QUEUED.value)
    if scope == "batch":
        pick = pick.where(jobs.c.batch_id == bindparam("g_batch"))
    elif scope == "shared":
        pick = pick.where(in_shared_batches())
    picked = (pick.order_by(jobs.c.batch_id, jobs.c.seq).limit(bindparam("b_limit"))
              .with_for_update(skip_locked=True, of=jobs).cte("picked"))
    return (guarded_update(Transition.CLAIM, JobState.RUNNING, jobs.c.id == picked.c.id)
            .values(attempts=jobs.c.attempts + 1, worker_id=bindparam("b_worker"),
                    worker_host=bindparam("b_host"), worker_pid=bindparam("b_pid"), child_pid=None,
                    lease_expires_at=bindparam("b_lease"), started_at=bindparam("b_now"), finished_at=None,
                    reason=None)
            .returning(*JOB_COLUMNS))


@functools.cache
def end_statement(transition: Transition) -> Update:
    """Record the end of an attempt (finish, retry or cancel) from its holder; target state in ``b_status``."""
    src = sorted(s.value for s in states.sources(transition))
    assert src == [JobState.RUNNING.value], transition
    values: dict[str, Any] = dict(status=bindparam("b_status"), exit_code=bindparam("b_exit"), finished_at=bindparam("b_end"),
                  started_at=bindparam("b_start"),          # the attempt's own start, not its claim
                  duration=bindparam("b_duration"), reason=bindparam("b_reason"), junit_xml=bindparam("b_xml"),
                  log_tail=bindparam("b_log"), output_dir=bindparam("b_out"), lease_expires_at=None)
    if transition is Transition.RETRY:
        values["retried"] = jobs.c.retried + 1
    return update(jobs).where(source_clause(transition), HOLDER).values(**values)
