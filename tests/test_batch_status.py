"""``status``'s figures (executor.batch.status) on real stores: the ETA goes by the batch's recent pace."""

from __future__ import annotations

import io
import time
from collections.abc import Iterator

import pytest

from executor.batch.status import ETA_JOBS, render, snapshot
from store.jobs import Batch, BatchOptions, JobResult, JobSpec, WorkerIdentity
from store.queue import QueueStore
from store.states import JobState

pytest_plugins = ["batch_stores"]            # the store_url fixture (SQLite, then PostgreSQL)


@pytest.fixture
def store(store_url: str) -> Iterator[QueueStore]:
    opened = QueueStore.open(store_url)
    yield opened
    opened.close()


def _batch(store: QueueStore, count: int) -> Batch:
    return store.create_batch(mode="local", input_dir="/in", output_dir="/out", host="h", command=(),
                              options=BatchOptions(),
                              specs=[JobSpec(f"j{i}", f"/in/j{i}.sce", "0" * 64, "x") for i in range(count)])


def _finish(store: QueueStore, batch: Batch, times: list[tuple[float, float]]) -> None:
    for job, (began, ended) in zip(store.claim(WorkerIdentity.current(), limit=len(times), batch_id=batch.id),
                                   times, strict=True):
        store.finish(job, JobResult(JobState.PASSED, 0, began, ended, junit_xml="<testsuite/>"))


def test_the_eta_goes_by_the_pace_of_the_latest_verdicts_not_by_the_jobs_a_runner_holds(store):
    """Four jobs ended within 8 s (from the first start to the last end) and a runner holds the other six
    (two running, four waiting for a slot, all ``running`` in the store): six more at that pace take 12 s.
    Counting the six held jobs as running at once would promise a third of that."""
    batch = _batch(store, 10)
    now = time.time()
    _finish(store, batch, [(now - 10 + 2 * i, now - 8 + 2 * i) for i in range(4)])
    assert snapshot(store, batch).eta_seconds is None                 # six queued, none running: no ETA
    store.claim(WorkerIdentity.current(), limit=6, batch_id=batch.id)
    snap = snapshot(store, batch)
    assert snap.counts[JobState.RUNNING] == 6 and snap.eta_seconds == pytest.approx(12.0)
    shown = io.StringIO()
    render(snap, shown)
    assert "  ETA 0:00:12\n" in shown.getvalue() and "  running    6\n" in shown.getvalue()
    for job in store.running(batch.id):
        store.finish(job, JobResult(JobState.PASSED, 0, now, now + 1, junit_xml="<testsuite/>"))
    assert snapshot(store, batch).eta_seconds == 0.0


def test_the_eta_forgets_the_pace_of_long_ago_and_needs_no_clock_in_common_with_the_workers(store):
    """Five jobs a day ago took an hour each; the latest ETA_JOBS took a second each, two at a time: the ETA
    is that of the latest ones. The workers' clock is an hour behind the asking host's: no matter."""
    batch = _batch(store, 5 + ETA_JOBS + 4)
    behind = time.time() - 3600
    _finish(store, batch, [(behind - 86400, behind - 86400 + 3600)] * 5)
    _finish(store, batch, [(behind + i // 2, behind + i // 2 + 1) for i in range(ETA_JOBS)])
    store.claim(WorkerIdentity.current(), limit=4, batch_id=batch.id)
    assert snapshot(store, batch).eta_seconds == pytest.approx(4 * (ETA_JOBS // 2) / ETA_JOBS)
