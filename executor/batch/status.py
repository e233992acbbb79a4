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


#: Seconds of recent ends the ETA goes by (the batch's pace now, not over its whole life).
ETA_WINDOW = 60.0


def snapshot(store: QueueStore, batch: Batch, now: float | None = None) -> StatusSnapshot:
    """Read counts and running jobs of ``batch`` and estimate the time left from its recent pace."""
    counts = store.counts(batch.id)
    running = Counter((j.worker_host or "?", j.worker_id or "?") for j in store.running(batch.id))
    remaining = counts[JobState.QUEUED] + counts[JobState.RUNNING]
    return StatusSnapshot(batch, counts, dict(running), 0.0 if remaining == 0 else
                          eta(store, batch.id, remaining, time.time() if now is None else now))


def eta(store: QueueStore, batch_id: int, remaining: int, now: float) -> float | None:
    """Seconds until ``remaining`` jobs have ended, at the pace jobs ended in the last :data:`ETA_WINDOW`
    seconds (None when none did: stopped, or not begun). The pace, not the jobs in state ``running`` and
    their mean time: a single-host run holds more jobs than it runs at once (the next ones for each
    slot), so those would promise an end many times too early."""
    since = now - ETA_WINDOW
    ended, first_start = store.recent_ends(batch_id, since)
    if ended == 0 or first_start is None:
        return None
    window = now - max(since, first_start)
    return remaining * window / ended if window > 0 else None


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
