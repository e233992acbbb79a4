"""The verdicts a results folder holds across the batches written into it.

A batch made by ``--rerun-failed`` or ``--only-new`` runs part of a folder and *continues* the batch
before it (``BatchOptions.continues``); a plain batch starts the folder afresh. The folder's verdicts
are those of the chain of batches back to that fresh start, the latest verdict of each job winning:
so ``test.xml`` keeps every job, however many reruns and top-ups followed (issue 31, items 5 and 8).

A later job replaces an earlier one of the same name only once it has a verdict: a rerun that was
interrupted before reaching a job leaves that job's earlier verdict in the report, not "not run".
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import TypeVar

from store.jobs import Batch, Job, JobSpec
from store.queue import QueueStore
from store.states import FINAL, JobState

T = TypeVar("T")

#: Jobs read with their results at a time.
_CHUNK = 500


def batch_chain(store: QueueStore, batch: Batch) -> list[Batch]:
    """``batch`` and the batches it continues, newest first (one batch when it starts afresh)."""
    chain = [batch]
    seen = {batch.id}
    while chain[-1].options.continues is not None and chain[-1].options.continues not in seen:
        earlier = store.batch(chain[-1].options.continues)
        seen.add(earlier.id)
        chain.append(earlier)
    return chain


def latest_jobs(store: QueueStore, batch: Batch, *, results: bool = True) -> Iterator[Job]:
    """The latest job of every name in the folder's chain of batches, in the order they first appeared.

    With ``results`` the jobs carry their JUnit XML and log tails: they are read :data:`_CHUNK` at a
    time, and a batch that continues none is streamed as it is, so neither a 100,000-job batch nor a
    long chain of them is ever held in memory with its results.
    """
    chain = batch_chain(store, batch)
    if len(chain) == 1:
        return store.iter_results(batch.id) if results else iter(store.jobs(batch.id))
    light = latest_of((store.jobs(each.id) for each in reversed(chain)),
                      lambda job: job.name, lambda job: job.status in FINAL)
    if not results:
        return iter(light)
    return (job for start in range(0, len(light), _CHUNK)
            for job in store.results_by_id([each.id for each in light[start:start + _CHUNK]]))


def latest_jobs_where(store: QueueStore, batch: Batch, keep: Callable[[Job], bool],
                      listed: Sequence[Job] | None = None) -> Iterator[Job]:
    """The jobs of :func:`latest_jobs` that ``keep`` accepts (judged without their results), with their
    results: only those are read with their reports. ``listed``: :func:`latest_jobs` without results,
    when the caller has it already."""
    light = list(latest_jobs(store, batch, results=False)) if listed is None else listed
    ids = [job.id for job in light if keep(job)]
    return (job for start in range(0, len(ids), _CHUNK) for job in store.results_by_id(ids[start:start + _CHUNK]))


def latest_of(batches: Iterable[Iterable[T]], name: Callable[[T], str], finished: Callable[[T], bool]) -> list[T]:
    """Of the jobs of ``batches`` (oldest batch first), the latest of each name: a later one replaces an
    earlier one only when it is ``finished``; the order is that in which the names first appeared."""
    latest: dict[str, T] = {}
    for jobs in batches:
        for job in jobs:
            key = name(job)
            if key not in latest or finished(job):
                latest[key] = job
    return list(latest.values())


def not_passed(store: QueueStore, batch: Batch) -> list[Job]:
    """The folder's jobs whose latest verdict is not a pass (``--rerun-failed`` runs these)."""
    return [job for job in latest_jobs(store, batch, results=False) if job.status is not JobState.PASSED]


def new_specs(store: QueueStore, batch: Batch | None, specs: Sequence[JobSpec]) -> list[JobSpec]:
    """``--only-new``: the specs whose file (same path, same content) has no verdict in the folder yet.

    A file that changed since it ran counts as new; so does one whose earlier job never finished.
    """
    if batch is None:
        return list(specs)
    done = {(job.scenario_path, job.scenario_sha) for job in latest_jobs(store, batch, results=False)
            if job.status in FINAL}
    return [spec for spec in specs if (spec.scenario_path, spec.scenario_sha) not in done]


def counts_of(jobs: Iterable[Job]) -> dict[JobState, int]:
    """How many of ``jobs`` are in each state."""
    counts = {state: 0 for state in JobState}
    for job in jobs:
        counts[job.status] += 1
    return counts
