"""Frozen records the queue hands out and takes back: batches, jobs, results, worker identities.

They are plain data built from database rows with ``from_row``; all SQL stays in :mod:`store.queue`.
"""

from __future__ import annotations

import hashlib
import json
import os
import socket
import uuid
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

from store import states
from store.states import JobState, Transition

if TYPE_CHECKING:
    from sqlalchemy import RowMapping

#: Bytes of a job's log kept in the store (the full log stays in the job's output folder).
LOG_TAIL_BYTES = 64 * 1024

#: Largest child JUnit XML stored; a bigger one is replaced by an error saying so.
JUNIT_MAX_BYTES = 8 * 1024 * 1024


@dataclass(frozen=True)
class BatchOptions:
    """How the jobs of a batch are run; stored with the batch so any worker runs them alike."""

    timeout: float | None = None
    retries: int = 0
    post_run: tuple[str, ...] = ()
    ignore_return_value: bool = False
    halt_on_failure: bool = False
    grace: float = 5.0
    shard: str | None = None
    #: Built-in runner only: every job runs step-based on this simulation (``scenario_execution --simulation``).
    simulation: str | None = None
    #: The batch this one adds to (``--rerun-failed``, ``--only-new``): the folder's report keeps that
    #: batch's verdicts (and those it continues) for the jobs this one does not run; None: a fresh start.
    continues: int | None = None
    #: ``--repeat``: attempts of each variant (each its own job, named ``<variant>@<k>``); with ``until_fail``
    #: the attempts not started yet are cancelled at the variant's first failure.
    repeat: int = 1
    until_fail: bool = False
    #: ``--pass-rate``: the share of a variant's attempts that must pass for the variant to pass.
    pass_rate: float = 1.0

    def to_json(self) -> str:
        data = asdict(self)
        data["post_run"] = list(self.post_run)
        return json.dumps(data, sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> BatchOptions:
        data = json.loads(text)
        known = {k: v for k, v in data.items() if k in cls.__dataclass_fields__}
        known["post_run"] = tuple(known.get("post_run") or ())
        return cls(**known)


@dataclass(frozen=True)
class Batch:
    """A set of jobs created by one command line, with the command and options to run them."""

    id: int
    created_at: float
    mode: str
    input_dir: str
    output_dir: str
    host: str
    command: tuple[str, ...]
    options: BatchOptions

    @classmethod
    def from_row(cls, row: Mapping[str, Any] | RowMapping) -> Batch:
        return cls(
            id=row["id"], created_at=row["created_at"], mode=row["mode"], input_dir=row["input_dir"],
            output_dir=row["output_dir"], host=row["host"], command=tuple(json.loads(row["command"])),
            options=BatchOptions.from_json(row["options"]),
        )


@dataclass(frozen=True)
class JobSpec:
    """One scenario file to enqueue."""

    name: str
    scenario_path: str
    scenario_sha: str
    scenario_text: str | None = None


@dataclass(frozen=True)
class Job:
    """A job row as read from the store; ``attempts`` doubles as the fencing token of the current lease."""

    id: int
    batch_id: int
    seq: int
    name: str
    scenario_path: str
    scenario_sha: str
    status: JobState
    attempts: int = 0
    retried: int = 0
    lost: int = 0
    worker_id: str | None = None
    worker_host: str | None = None
    worker_pid: int | None = None
    child_pid: int | None = None
    lease_expires_at: float | None = None
    queued_at: float | None = None
    started_at: float | None = None
    finished_at: float | None = None
    duration: float | None = None
    exit_code: int | None = None
    reason: str | None = None
    output_dir: str | None = None
    junit_xml: str | None = field(default=None, repr=False)
    log_tail: str | None = field(default=None, repr=False)

    @classmethod
    def from_row(cls, row: Mapping[str, Any] | RowMapping) -> Job:
        data = row if isinstance(row, dict) else dict(row)     # a RowMapping answers ``in`` slowly
        values = {name: data[name] for name in cls.__dataclass_fields__ if name in data}
        values["status"] = JobState(values["status"])
        return cls(**values)


@dataclass(frozen=True)
class JobResult:
    """What one attempt of a job produced; written to the store in one transaction."""

    status: JobState
    exit_code: int | None
    started_at: float
    finished_at: float
    reason: str | None = None
    junit_xml: str | None = field(default=None, repr=False)
    log_tail: str | None = field(default=None, repr=False)
    output_dir: str | None = None
    log_path: str | None = None
    coverage_json: str | None = field(default=None, repr=False)   # the attempt's coverage.json (not stored yet)

    @property
    def duration(self) -> float:
        return max(0.0, self.finished_at - self.started_at)


@dataclass(frozen=True)
class JobEnd:
    """How an attempt ends in the store: its result and the transition that records it (finish, retry, cancel)."""

    job: Job
    result: JobResult
    transition: Transition

    def __post_init__(self) -> None:
        states.check(self.transition, self.target)

    @property
    def target(self) -> JobState:
        """The job's state once recorded: the verdict, queued again (a retry) or cancelled."""
        if self.transition is Transition.RETRY:
            return JobState.QUEUED
        if self.transition is Transition.CANCEL:
            return JobState.CANCELLED
        return self.result.status


@dataclass(frozen=True)
class WorkerIdentity:
    """Who holds a lease: a unique id plus the host and process, so a dead local holder can be detected.

    The id is ``host:pid:node:nonce``; ``node`` names this boot of this machine and its process-id
    namespace, so process ids recorded by another container or before a reboot are never taken for
    processes here (they must not be signalled).
    """

    id: str
    host: str
    pid: int
    node: str = ""

    @classmethod
    def current(cls) -> WorkerIdentity:
        """This process; the host name comes from ``$SCENARIO_WORKER_HOST`` if set (e.g. a node name)."""
        host = os.environ.get("SCENARIO_WORKER_HOST") or socket.gethostname()
        pid = os.getpid()
        node = _node_token()
        return cls(id=f"{host}:{pid}:{node}:{uuid.uuid4().hex[:8]}", host=host, pid=pid, node=node)

    def same_node(self, worker_id: str | None) -> bool:
        """Whether ``worker_id`` was issued on this machine, boot and process namespace."""
        parts = (worker_id or "").split(":")
        return len(parts) == 4 and parts[0] == self.host and parts[2] == self.node and bool(self.node)


def _node_token() -> str:
    """A short token for this boot of this machine and this process-id namespace ('' if unknown)."""
    try:
        with open("/proc/sys/kernel/random/boot_id", encoding="ascii") as handle:
            boot = handle.read().strip()
        namespace = os.stat("/proc/self/ns/pid").st_ino
    except OSError:
        return ""
    return hashlib.sha256(f"{boot}/{namespace}".encode()).hexdigest()[:10]


@dataclass(frozen=True)
class Reclaimed:
    """A job taken back from a holder that lost its lease, with the child process it may have left."""

    job_id: int
    attempt: int
    worker_id: str | None
    worker_host: str | None
    child_pid: int | None
    status: JobState
