"""How each variant fared across the batches of a store: the facts flaky detection and history read.

A variant's identity across batches is its job name and the SHA-256 of its scenario file: the same
file run again (tonight's sweep of the same ``.sce``) is the same variant, an edited one is not. Only
finished jobs count. The queries group in the database, so 100 batches of 1,000 jobs come back as at
most one row per (name, content, state).
"""

from __future__ import annotations

from typing import NamedTuple

from sqlalchemy import Engine, case, func, select

from store.queue_tables import batches, jobs
from store.states import FINAL


class OutcomeCount(NamedTuple):
    """How many (``total``) finished jobs named ``name`` with content ``sha`` ended in ``status``."""

    name: str
    sha: str
    status: str
    total: int


def ran_before(engine: Engine, batch_id: int) -> bool:
    """Whether a batch before ``batch_id`` ran (to a verdict) any scenario content that batch runs: without
    one, and without repeats, no variant of the batch can be flaky (one statement, stops at the first)."""
    finals = [state.value for state in FINAL]
    contents = select(jobs.c.scenario_sha).where(jobs.c.batch_id == batch_id).scalar_subquery()
    stmt = (select(jobs.c.id).where(jobs.c.scenario_sha.in_(contents), jobs.c.status.in_(finals),
                                    jobs.c.batch_id < batch_id).limit(1))
    with engine.connect() as conn:
        return conn.execute(stmt).first() is not None


def variant_keys(engine: Engine, batch_id: int) -> set[tuple[str, str]]:
    """The (name, content) of every job of a batch: what identifies its variants, read without the rest
    of each job's row."""
    with engine.connect() as conn:
        return {(row[0], row[1]) for row in conn.execute(
            select(jobs.c.name, jobs.c.scenario_sha).where(jobs.c.batch_id == batch_id))}


def outcome_counts(engine: Engine, batch_id: int) -> list[OutcomeCount]:
    """The finished jobs of every batch up to ``batch_id`` (inclusive) whose scenario content is that of
    a job of batch ``batch_id``, counted per name, content and state (one statement: the database
    matches the contents once, with no list of values sent)."""
    finals = [state.value for state in FINAL]
    contents = select(jobs.c.scenario_sha).where(jobs.c.batch_id == batch_id).scalar_subquery()
    stmt = (select(jobs.c.name, jobs.c.scenario_sha, jobs.c.status, func.count())
            .where(jobs.c.scenario_sha.in_(contents), jobs.c.status.in_(finals), jobs.c.batch_id <= batch_id)
            .group_by(jobs.c.name, jobs.c.scenario_sha, jobs.c.status))
    with engine.connect() as conn:
        return [OutcomeCount(*row) for row in conn.execute(stmt).all()]


class BatchCounts(NamedTuple):
    """A batch with its number of jobs, finished jobs and passed jobs."""

    batch_id: int
    created_at: float
    output_dir: str
    options: str
    jobs: int
    finished: int
    passed: int


def batch_counts(engine: Engine, *, last: int | None = None) -> list[BatchCounts]:
    """Every batch of the store (or the ``last`` ones), oldest first, with its job counts: one query."""
    finals = [state.value for state in FINAL]
    finished = func.sum(case((jobs.c.status.in_(finals), 1), else_=0))
    passed = func.sum(case((jobs.c.status == "passed", 1), else_=0))
    stmt = (select(batches.c.id, batches.c.created_at, batches.c.output_dir, batches.c.options,
                   func.count(jobs.c.id), func.coalesce(finished, 0), func.coalesce(passed, 0))
            .select_from(batches.outerjoin(jobs, jobs.c.batch_id == batches.c.id))
            .group_by(batches.c.id).order_by(batches.c.id.desc()))
    if last is not None:
        stmt = stmt.limit(last)
    with engine.connect() as conn:
        rows = conn.execute(stmt).all()
    return [BatchCounts(*row) for row in reversed(rows)]
