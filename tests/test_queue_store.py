"""The queue's verbs and state machine on real databases: one suite over SQLite and PostgreSQL."""

from __future__ import annotations

import multiprocessing
import subprocess
import sys
import time

import pytest
from batch_fixtures import sqlite_url

from store import states
from store.database import StoreError, ensure_schema, open_engine
from store.jobs import BatchOptions, JobResult, JobSpec, WorkerIdentity
from store.queue import LeaseLost, QueueStore
from store.queue_tables import QUEUE_TABLES
from store.states import UNCHARGED_CLAIMS, JobState, Transition, TransitionError

pytest_plugins = ["batch_stores"]            # the store_url and pg_url fixtures


def _store(url: str, count: int = 5, mode: str = "local"):
    store = QueueStore.open(url)
    batch = store.create_batch(mode=mode, input_dir="/in", output_dir="/out", host="h",
                               command=["run", "{SCENARIO}", "{OUTPUT_DIR}"], options=BatchOptions(retries=1),
                               specs=[JobSpec(f"j{i}", f"/in/j{i}.sce", "0" * 64, "text") for i in range(count)])
    return store, batch


def _result(status: JobState = JobState.PASSED, exit_code: int | None = 0) -> JobResult:
    now = time.time()
    return JobResult(status, exit_code, now - 1, now, junit_xml="<testsuite/>", log_tail="tail")


def _worker(name: str) -> WorkerIdentity:
    return WorkerIdentity(id=f"{name}-id", host=name, pid=1)


def test_state_machine_table():
    assert states.check(Transition.FINISH, JobState.PASSED) is JobState.PASSED
    with pytest.raises(TransitionError):
        states.check(Transition.FINISH, JobState.QUEUED)
    assert states.allowed(JobState.QUEUED, JobState.RUNNING)
    assert states.allowed(JobState.CANCELLED, JobState.QUEUED)
    assert not states.allowed(JobState.PASSED, JobState.QUEUED)        # a verdict is never replaced
    assert not any(states.allowed(final, other) for final in states.FINAL for other in JobState)
    assert states.RETRYABLE == {JobState.ERROR, JobState.TIMEOUT}


def test_claim_takes_exactly_the_limit_in_file_order(store_url):
    store, batch = _store(store_url)
    try:
        first = store.claim(_worker("a"), limit=2, batch_id=batch.id)
        assert [j.name for j in first] == ["j0", "j1"]
        assert all(j.status is JobState.RUNNING and j.attempts == 1 and j.worker_id == "a-id" for j in first)
        second = store.claim(_worker("b"), limit=10, batch_id=batch.id)
        assert [j.name for j in second] == ["j2", "j3", "j4"]
        assert store.claim(_worker("c"), batch_id=batch.id) == []
        assert store.counts(batch.id)[JobState.RUNNING] == 5
    finally:
        store.close()


def test_results_only_from_the_lease_holder_and_only_once(store_url):
    store, batch = _store(store_url, count=2)
    try:
        a, b = _worker("a"), _worker("b")
        [job] = store.claim(a, batch_id=batch.id)
        assert store.started(job, 4242)
        store.finish(job, _result())
        with pytest.raises(LeaseLost):
            store.finish(job, _result(JobState.FAILED, 1))           # idempotent: one final result per job
        [late] = store.claim(a, batch_id=batch.id)
        assert store.started(late, 4243)
        reclaimed = store.reclaim_expired(now=time.time() + 3600)
        assert [(r.job_id, r.worker_id, r.status) for r in reclaimed] == [(late.id, "a-id", JobState.QUEUED)]
        [taken] = store.claim(b, batch_id=batch.id)
        assert taken.id == late.id and taken.attempts == 2
        with pytest.raises(LeaseLost):
            store.finish(late, _result())                            # the old holder's late result is refused
        store.finish(taken, _result(JobState.FAILED, 1))
        jobs = {j.name: j for j in store.jobs(batch.id, results=True)}
        assert jobs["j0"].status is JobState.PASSED and jobs["j0"].junit_xml == "<testsuite/>"
        assert jobs["j1"].status is JobState.FAILED and jobs["j1"].worker_id == "b-id"
        assert [a["outcome"] for a in store.attempts(late.id)] == ["lost", "failed"]
    finally:
        store.close()


def test_heartbeat_keeps_the_lease_and_expiry_is_bounded(store_url):
    store, batch = _store(store_url, count=1)
    try:
        worker = _worker("a")
        for round_ in range(3):
            [job] = store.claim(worker, batch_id=batch.id, lease=0.5)
            assert store.started(job, 4242)
            assert store.heartbeat(worker, lease=30) == {job.id}
            assert store.reclaim_expired(now=time.time() + 5) == []     # the heartbeat extended it
            reclaimed = store.reclaim_expired(now=time.time() + 60)
            assert len(reclaimed) == 1
            expected = JobState.ERROR if round_ == 2 else JobState.QUEUED
            assert reclaimed[0].status is expected
        [job] = store.jobs(batch.id)
        assert job.status is JobState.ERROR and job.lost == 3 and "3 times" in job.reason
        assert store.heartbeat(worker) == set()
    finally:
        store.close()


def test_a_job_taken_back_before_it_started_is_not_charged_with_a_lost_attempt(store_url):
    """A runner killed while it held jobs for its next slots: only the job it had started lost a run."""
    store, batch = _store(store_url, count=3)
    try:
        for kill in range(3):                        # as many kills as a started job survives
            ran, *held = store.claim(_worker(f"runner{kill}"), limit=3, batch_id=batch.id)
            assert store.started(ran, 4242)
            reclaimed = store.reclaim_worker(f"runner{kill}-id", "the runner ended")
            assert {(r.job_id, r.child_pid) for r in reclaimed} == \
                {(ran.id, 4242), *((job.id, None) for job in held)}
            if kill < 2:
                assert {r.status for r in reclaimed} == {JobState.QUEUED}
        jobs = {j.name: j for j in store.jobs(batch.id)}
        assert jobs["j0"].status is JobState.ERROR and jobs["j0"].lost == 3 and "3 times" in jobs["j0"].reason
        for name in ("j1", "j2"):                    # held three times, started never: queued, uncharged
            job = jobs[name]
            assert job.status is JobState.QUEUED and job.lost == 0, job
            assert "before it started" in job.reason
            assert store.attempts(job.id) == []
        assert [a["outcome"] for a in store.attempts(jobs["j0"].id)] == ["lost"] * 3
        [again] = store.claim(_worker("last"), batch_id=batch.id)
        assert again.name == "j1" and again.attempts == 4 and again.child_pid is None
    finally:
        store.close()


def test_a_job_whose_holder_is_always_lost_before_its_start_is_recorded_still_ends(store_url):
    """A job whose every run ends its runner at once (before its start is written) is not retried for
    ever: after its first UNCHARGED_CLAIMS claims a loss is charged, and the third charged one ends it."""
    store, batch = _store(store_url, count=1)
    try:
        claims = 0
        while True:
            [job] = store.claim(_worker("victim"), batch_id=batch.id)
            claims += 1
            [taken] = store.reclaim_worker("victim-id", "the runner ended")
            if taken.status is JobState.ERROR:
                break
            assert claims < 50
        [job] = store.jobs(batch.id)
        assert claims == UNCHARGED_CLAIMS + 3 and job.lost == 3 and "keeps losing its worker" in job.reason
        assert [a["outcome"] for a in store.attempts(job.id)] == ["lost"] * 3
    finally:
        store.close()


def test_retry_cancel_halt_resume(store_url):
    store, batch = _store(store_url, count=4)
    try:
        worker = _worker("a")
        [job] = store.claim(worker, batch_id=batch.id)
        store.retry(job, _result(JobState.ERROR, None))
        [again] = store.claim(worker, batch_id=batch.id)
        assert again.id == job.id and again.attempts == 2 and again.retried == 1
        store.cancel(again, _result(JobState.CANCELLED, -2))
        assert store.halt(batch.id) == 3
        assert store.counts(batch.id)[JobState.CANCELLED] == 4
        assert store.claim(worker, batch_id=batch.id) == []
        assert store.resume(batch.id) == 4
        assert store.counts(batch.id)[JobState.QUEUED] == 4
        assert [a["outcome"] for a in store.attempts(job.id)] == ["error", "cancelled"]
        other = _worker("b")
        phantom = store.claim(other, limit=2, batch_id=batch.id)     # e.g. the commit's reply was lost
        assert store.release(_worker("a"), [j.id for j in phantom]) == 0   # not a's to give back
        assert store.release(other, [j.id for j in phantom]) == 2
        assert store.counts(batch.id)[JobState.QUEUED] == 4
    finally:
        store.close()


def test_worker_claims_only_shared_batches(store_url):
    store, local = _store(store_url, count=2, mode="local")
    try:
        shared = store.create_batch(mode="shared", input_dir="/in", output_dir="/out", host="h",
                                    command=["x"], options=BatchOptions(), specs=[JobSpec("s", "/in/s.sce", "0")])
        claimed = store.claim(_worker("w"), limit=5, shared_only=True)
        assert [j.batch_id for j in claimed] == [shared.id]
        assert store.counts(local.id)[JobState.QUEUED] == 2
        assert store.latest_batch(mode="shared").id == shared.id
        assert store.scenario_text(claimed[0].id) is None
    finally:
        store.close()


_OPEN = """
import sys
from store.queue import QueueStore
QueueStore.open(sys.argv[1]).close()
print("ok")
"""


@pytest.mark.slow
def test_many_processes_create_the_schema_at_once(store_url):
    procs = [subprocess.Popen([sys.executable, "-c", _OPEN, store_url], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(6)]
    outputs = [p.communicate(timeout=60) for p in procs]
    assert all(p.returncode == 0 for p in procs), outputs
    store, batch = _store(store_url, count=1)
    store.close()


def _open_at_the_barrier(url: str, barrier, failures) -> None:
    engine = open_engine(url)           # what QueueStore.open does, with its first connection at the barrier
    barrier.wait(timeout=60)
    try:
        ensure_schema(engine, QUEUE_TABLES)
    except StoreError as exc:
        failures.put(str(exc))
    finally:
        engine.dispose()


def test_processes_opening_one_new_sqlite_store_at_the_same_moment_all_succeed(tmp_path):
    # The processes leave a barrier together, so their switches to WAL mode meet: SQLite's deadlock
    # guard then answers "database is locked" at once, busy timeout or not (about one round in five
    # failed so before the switch was retried). Forked, to leave the barrier within microseconds.
    context = multiprocessing.get_context("fork")
    failures = context.Queue()
    for round_ in range(20):
        (tmp_path / str(round_)).mkdir()
        url = sqlite_url(tmp_path / str(round_))
        barrier = context.Barrier(6)
        procs = [context.Process(target=_open_at_the_barrier, args=(url, barrier, failures), daemon=True)
                 for _ in range(6)]
        try:
            for proc in procs:
                proc.start()
            deadline = time.monotonic() + 120
            for proc in procs:
                proc.join(timeout=max(0.0, deadline - time.monotonic()))
        finally:
            for proc in procs:
                if proc.is_alive():
                    proc.kill()
        assert [proc.exitcode for proc in procs] == [0] * 6
        assert failures.empty(), failures.get()


def test_incompatible_schema_version_is_refused(tmp_path):
    url = sqlite_url(tmp_path)
    QueueStore.open(url).close()
    import sqlite3

    conn = sqlite3.connect(tmp_path / "store.db")
    conn.execute("UPDATE store_meta SET schema_version = schema_version + 1")
    conn.commit()
    conn.close()
    with pytest.raises(StoreError, match="schema version"):
        QueueStore.open(url)


def test_driver_statements_bind_as_sqlalchemy_does_and_refuse_a_text_that_depends_on_the_values():
    from sqlalchemy import bindparam, select
    from sqlalchemy.dialects import postgresql, sqlite

    from store.driver_statements import DriverStatement
    from store.queue_statements import end_statement
    from store.queue_tables import jobs

    values = {"b_status": "passed", "b_exit": 0, "b_end": 2, "b_start": 1, "b_duration": 1, "b_reason": None,
              "b_xml": "<x/>",
              "b_log": "", "b_out": "/o", "g_job": 7, "g_holder": "w", "g_attempt": 1}
    on_sqlite = DriverStatement(end_statement(Transition.FINISH), sqlite.dialect())
    params = on_sqlite.parameters(values)
    assert on_sqlite.sql.count("?") == len(params)
    assert 2.0 in params and isinstance(params[params.index(2.0)], float)      # SQLite gets floats, as before
    assert "running" in params and 7 in params and "w" in params             # the guard's own literal is filled in
    on_postgres = DriverStatement(end_statement(Transition.FINISH), postgresql.dialect())
    assert on_postgres.parameters(values)["g_job"] == 7 and "%(g_job)s" in on_postgres.sql
    expanding = select(jobs.c.id).where(jobs.c.id.in_(bindparam("ids", expanding=True)))
    with pytest.raises(ValueError, match="not a fixed statement"):
        DriverStatement(expanding, sqlite.dialect())
