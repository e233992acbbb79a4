"""``status``: counts per state, running jobs per worker and host, and an ETA, for people or scripts.

A rich table on a terminal (without colours under ``NO_COLOR``), plain aligned text otherwise.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass, field
from typing import TextIO

from executor.output.terminal import wants_rich
from store.jobs import Batch
from store.queue import QueueStore
from store.states import JobState


@dataclass(frozen=True)
class StatusSnapshot:
    """The state of one batch at one moment."""

    batch: Batch
    counts: dict[JobState, int]
    running: dict[tuple[str, str], int] = field(default_factory=dict)   # (host, worker id) -> jobs
    eta_seconds: float | None = None

    @property
    def total(self) -> int:
        return sum(self.counts.values())


#: Verdicts the ETA goes by: the batch's pace now, not over its whole life.
ETA_JOBS = 20


def snapshot(store: QueueStore, batch: Batch) -> StatusSnapshot:
    """Read counts and running jobs of ``batch`` and estimate the time left from its recent pace."""
    counts = store.counts(batch.id)
    running = Counter((j.worker_host or "?", j.worker_id or "?") for j in store.running(batch.id))
    remaining = counts[JobState.QUEUED] + counts[JobState.RUNNING]
    eta_seconds = 0.0 if remaining == 0 else eta(store, batch.id, remaining) if running else None
    return StatusSnapshot(batch, counts, dict(running), eta_seconds)


def eta(store: QueueStore, batch_id: int, remaining: int) -> float | None:
    """Seconds until ``remaining`` jobs have ended, at the pace of the latest :data:`ETA_JOBS` verdicts
    (from the earliest start to the latest end among them, by the workers' clocks: the host asking
    needs no clock in common with them); None before a verdict. The pace, not the jobs in state
    ``running`` and their mean time: a single-host run holds more jobs than it runs at once (the next
    ones for each slot), so those would promise an end many times too early."""
    ended, span = store.recent_pace(batch_id, ETA_JOBS)
    if ended == 0 or span is None or span <= 0:
        return None
    return remaining * span / ended


def _eta_text(seconds: float | None) -> str:
    if seconds is None:
        return "unknown"
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}"


def render(snap: StatusSnapshot, stream: TextIO) -> None:
    """Print a snapshot: a rich table on a terminal, plain lines otherwise."""
    created = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(snap.batch.created_at))
    head = (f"batch {snap.batch.id} ({snap.batch.mode}, created {created} on {snap.batch.host}): "
            f"{snap.total} job(s), output {snap.batch.output_dir}")
    if wants_rich(stream):
        from rich.console import Console
        from rich.table import Table

        console = Console(file=stream)
        console.print(head, markup=False, highlight=False)
        states = Table(title="jobs per state")
        states.add_column("state")
        states.add_column("jobs", justify="right")
        for state in JobState:
            states.add_row(state.value, str(snap.counts[state]))
        console.print(states)
        if snap.running:
            workers = Table(title="running jobs per worker")
            for name in ("host", "worker", "jobs"):
                workers.add_column(name, justify="right" if name == "jobs" else "left")
            for (host, worker), count in sorted(snap.running.items()):
                workers.add_row(host, worker, str(count))
            console.print(workers)
        console.print(f"ETA {_eta_text(snap.eta_seconds)}", markup=False)
        return
    print(head, file=stream)
    for state in JobState:
        print(f"  {state.value:<10} {snap.counts[state]}", file=stream)
    for (host, worker), count in sorted(snap.running.items()):
        print(f"  running on {host} by {worker}: {count}", file=stream)
    print(f"  ETA {_eta_text(snap.eta_seconds)}", file=stream, flush=True)
