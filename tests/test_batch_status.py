"""``status``'s figures (executor.batch.status) on real stores: the ETA goes by the batch's recent pace."""

from __future__ import annotations

import io
import time
from collections.abc import Iterator

import pytest

from executor.batch.status import ETA_WINDOW, render, snapshot
from store.jobs import BatchOptions, JobResult, JobSpec, WorkerIdentity
from store.queue import QueueStore
from store.states import JobState

pytest_plugins = ["batch_stores"]            # the store_url fixture (SQLite, then PostgreSQL)


@pytest.fixture
def store(store_url: str) -> Iterator[QueueStore]:
    opened = QueueStore.open(store_url)
    yield opened
    opened.close()


def test_the_eta_goes_by_the_pace_jobs_ended_lately_not_by_the_jobs_a_runner_holds(store):
    """Four jobs ended over the last 10 s and a runner holds the other six (two running, four waiting for
    a slot, all ``running`` in the store): six more at that pace take 15 s. Counting the six held jobs as
    running at once would promise about a third of that."""
    batch = store.create_batch(mode="local", input_dir="/in", output_dir="/out", host="h", command=(),
                               options=BatchOptions(),
                               specs=[JobSpec(f"j{i}", f"/in/j{i}.sce", "0" * 64, "x") for i in range(10)])
    worker = WorkerIdentity.current()
    now = time.time()
    for index, job in enumerate(store.claim(worker, limit=4, batch_id=batch.id)):
        store.finish(job, JobResult(JobState.PASSED, 0, now - 10 + 2 * index, now - 8 + 2 * index,
                                    junit_xml="<testsuite/>"))
    assert snapshot(store, batch, now).eta_seconds == pytest.approx(15.0)        # six queued: the same
    store.claim(worker, limit=6, batch_id=batch.id)
    snap = snapshot(store, batch, now)
    assert snap.counts[JobState.RUNNING] == 6 and snap.eta_seconds == pytest.approx(15.0)
    shown = io.StringIO()
    render(snap, shown)
    assert "  ETA 0:00:15\n" in shown.getvalue() and "  running   " in shown.getvalue()
    assert snapshot(store, batch, now + ETA_WINDOW + 1).eta_seconds is None       # nothing ended lately
    for job in store.running(batch.id):
        store.finish(job, JobResult(JobState.PASSED, 0, now, now + 1, junit_xml="<testsuite/>"))
    assert snapshot(store, batch, now + 2).eta_seconds == 0.0
