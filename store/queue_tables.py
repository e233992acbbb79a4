"""Tables of the batch queue: one row per batch, one per job, one per attempt of a job.

Declared on the shared :data:`store.database.metadata`, so a store holds variation records and
batch queues side by side. Times are seconds since the epoch (floats) from the writer's clock;
hosts sharing a store are expected to keep their clocks in sync (NTP), as leases compare them.
"""

from __future__ import annotations

from sqlalchemy import (
    Column,
    Float,
    ForeignKey,
    Index,
    Integer,
    String,
    Table,
    Text,
    UniqueConstraint,
)

from store.database import metadata

batches = Table(
    "batches",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("created_at", Float, nullable=False),
    # "local": run by the command that created it; "shared": run by `worker` processes on any host.
    Column("mode", String(16), nullable=False),
    Column("input_dir", Text, nullable=False),
    Column("output_dir", Text, nullable=False),
    Column("host", String(255), nullable=False),
    Column("command", Text, nullable=False),       # JSON list of argument templates
    Column("options", Text, nullable=False),       # JSON object, see store.jobs.BatchOptions
)

jobs = Table(
    "jobs",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("batch_id", Integer, ForeignKey("batches.id", ondelete="CASCADE"), nullable=False),
    Column("seq", Integer, nullable=False),
    Column("name", String(255), nullable=False),
    Column("scenario_path", Text, nullable=False),
    Column("scenario_sha", String(64), nullable=False),
    Column("scenario_text", Text),
    Column("status", String(16), nullable=False),
    Column("attempts", Integer, nullable=False, default=0),   # attempts started; the lease's fencing token
    Column("retried", Integer, nullable=False, default=0),    # attempts repeated after an infrastructure error
    Column("lost", Integer, nullable=False, default=0),       # attempts whose holder was lost, charged
    Column("worker_id", String(255)),
    Column("worker_host", String(255)),
    Column("worker_pid", Integer),
    Column("child_pid", Integer),
    Column("lease_expires_at", Float),
    Column("queued_at", Float, nullable=False),
    Column("started_at", Float),
    Column("finished_at", Float),
    Column("duration", Float),
    Column("exit_code", Integer),
    Column("reason", Text),
    Column("output_dir", Text),
    Column("junit_xml", Text),
    Column("log_tail", Text),
    Index("ix_jobs_claim", "status", "batch_id", "seq"),
    Index("ix_jobs_batch", "batch_id", "seq"),
    Index("ix_jobs_worker", "worker_id"),
)

job_attempts = Table(
    "job_attempts",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("job_id", Integer, ForeignKey("jobs.id", ondelete="CASCADE"), nullable=False),
    Column("attempt", Integer, nullable=False),
    # a job state for attempts that ended with a verdict, or "lost" when the holder of a started one was lost
    Column("outcome", String(16), nullable=False),
    Column("exit_code", Integer),
    Column("started_at", Float),
    Column("finished_at", Float),
    Column("worker_id", String(255)),
    Column("host", String(255)),
    Column("log_path", Text),
    Column("reason", Text),
    UniqueConstraint("job_id", "attempt", name="uq_job_attempts_attempt"),
)

#: The tables the queue needs, in creation order.
QUEUE_TABLES = [batches, jobs, job_attempts]
