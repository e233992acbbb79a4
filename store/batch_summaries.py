"""What a finished batch's coverage came to, kept so history over many batches reads one row each.

``batch_summaries`` holds per batch its overall grade and holes as the coverage report computed them
when the batch's report was written, with the numbers of runs and variants, passed ones and flaky
ones. Building the coverage of 1,000 runs costs tens of milliseconds; history over 100 batches reads
100 rows instead. A batch without a row (a store written by an older release, a shared batch nobody
reported) is computed when asked for (see ``executor.batch.history``).
"""

from __future__ import annotations

import time
from collections.abc import Collection
from typing import NamedTuple

from sqlalchemy import Column, Engine, Float, ForeignKey, Integer, Table, delete, insert, inspect, select

from store.database import ensure_schema, metadata

batch_summaries = Table(
    "batch_summaries",
    metadata,
    Column("batch_id", Integer, ForeignKey("batches.id", ondelete="CASCADE"), primary_key=True),
    Column("recorded_at", Float, nullable=False),
    Column("runs", Integer, nullable=False),
    Column("passed", Integer, nullable=False),
    Column("variants", Integer, nullable=False),
    Column("variants_passed", Integer, nullable=False),
    Column("flaky", Integer, nullable=False),
    Column("grade", Float),              # None: no graded item
    Column("holes", Integer),
)


class BatchSummary(NamedTuple):
    """One batch's figures as recorded at the end of its report (grade in percent, None when ungraded)."""

    batch_id: int
    runs: int
    passed: int
    variants: int
    variants_passed: int
    flaky: int
    grade: float | None
    holes: int | None


def record_summary(engine: Engine, summary: BatchSummary) -> None:
    """Keep ``summary`` (replacing the batch's earlier one: a report written again after ``--resume``)."""
    ensure_schema(engine, [batch_summaries])
    with engine.begin() as conn:
        conn.execute(delete(batch_summaries).where(batch_summaries.c.batch_id == summary.batch_id))
        conn.execute(insert(batch_summaries).values(recorded_at=time.time(), **summary._asdict()))


def read_summaries(engine: Engine, batch_ids: Collection[int]) -> dict[int, BatchSummary]:
    """The recorded summaries of these batches (a store without the table has none)."""
    if not batch_ids or not inspect(engine).has_table(batch_summaries.name):
        return {}
    columns = [batch_summaries.c[name] for name in BatchSummary._fields]
    with engine.connect() as conn:
        rows = conn.execute(select(*columns).where(batch_summaries.c.batch_id.in_(sorted(batch_ids)))).all()
    return {row[0]: BatchSummary(*row) for row in rows}
