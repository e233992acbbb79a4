"""Many workers on one queue, on SQLite and PostgreSQL: exactly-once claims, lost workers, the CLI verbs."""

from __future__ import annotations

import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

import pytest
from batch_fixtures import child_command, cli_env, ledger, run_cli, start_cli, write_child, write_scenarios

from store.jobs import BatchOptions, JobSpec
from store.queue import QueueStore
from store.states import JobState

pytest_plugins = ["batch_stores"]            # the store_url and pg_url fixtures

# A worker process driving the store API directly: claim, append to the ledger, finish — no child
# process, so 2,000 jobs take seconds and the test measures the queue, not process start-up.
_QUEUE_WORKER = r"""
import os, sys, time
from store.jobs import JobResult, WorkerIdentity
from store.queue import QueueStore
from store.states import JobState
url, ledger, go = sys.argv[1], sys.argv[2], sys.argv[3]
store = QueueStore.open(url)
me = WorkerIdentity.current()
print("ready", flush=True)
while not os.path.exists(go):                 # start together, so every worker competes
    time.sleep(0.005)
fd = os.open(ledger, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
done = 0
while True:
    jobs = store.claim(me, limit=2, shared_only=True)
    if not jobs:
        counts = store.counts(shared_only=True)
        if counts[JobState.QUEUED] == 0:
            break
        continue
    for job in jobs:
        os.write(fd, ("%d %s\n" % (job.id, me.id)).encode())
        now = time.time()
        store.finish(job, JobResult(JobState.PASSED, 0, now, now, junit_xml="<testsuite/>"))
        done += 1
print(done)
"""


@pytest.mark.slow
def test_four_workers_2000_jobs_each_claimed_and_finished_once(store_url, tmp_path):
    store = QueueStore.open(store_url)
    batch = store.create_batch(mode="shared", input_dir="/in", output_dir="/out", host="h", command=["x"],
                               options=BatchOptions(),
                               specs=[JobSpec(f"j{i:04d}", f"/in/j{i:04d}.sce", "0") for i in range(2000)])
    store.close()
    ledger_file = tmp_path / "claims.txt"
    go = tmp_path / "go"
    procs = [subprocess.Popen([sys.executable, "-c", _QUEUE_WORKER, store_url, str(ledger_file), str(go)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(4)]
    assert all(p.stdout.readline().strip() == "ready" for p in procs)
    go.touch()
    outputs = [p.communicate(timeout=180) for p in procs]
    assert all(p.returncode == 0 for p in procs), outputs
    per_worker = [int(out) for out, _ in outputs]
    assert sum(per_worker) == 2000
    lines = ledger_file.read_text().splitlines()
    claims = Counter(line.split()[0] for line in lines)
    assert len(claims) == 2000 and set(claims.values()) == {1}
    assert len({line.split()[1] for line in lines}) >= 2                 # they really competed

    store = QueueStore.open(store_url)
    try:
        jobs = store.jobs(batch.id)
        assert {str(j.id) for j in jobs} == set(claims)
        assert all(j.status is JobState.PASSED and j.attempts == 1 for j in jobs)
        assert all(len(store.attempts(j.id)) == 1 for j in jobs[:50])
    finally:
        store.close()


def _enqueue(tmp_path: Path, store_url: str, specs: dict[str, str], env) -> None:
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", specs)
    result = run_cli(["-i", "in", "-o", "results", "--store", store_url, "--enqueue-only", "--",
                      *child_command(child)], tmp_path, env)
    assert result.returncode == 0, result.stderr
    assert f"{len(specs)} job(s) queued" in result.stdout
    assert not (tmp_path / "results" / "test.xml").exists()


@pytest.mark.slow
def test_enqueue_workers_status_report(store_url, tmp_path):
    env = cli_env(tmp_path)
    names = [f"s{i:02d}" for i in range(24)]
    _enqueue(tmp_path, store_url, {n: "sleep=0.05" if n != "s07" else "xml=fail" for n in names}, env)
    status = run_cli(["status", "--store", store_url], tmp_path, env)
    assert status.returncode == 0 and "queued     24" in status.stdout, status.stdout

    workers = [start_cli(["worker", "--store", store_url, "-j", "2", "--poll", "0.1",
                          "-o" if i == 0 else "--output-dir", f"host{i}"], tmp_path, env) for i in range(2)]
    outputs = [w.communicate(timeout=120)[0] for w in workers]
    assert all(w.returncode == 0 for w in workers), outputs
    assert all("worker done" in out for out in outputs), outputs
    assert ledger(tmp_path) == Counter({n: 1 for n in names})
    produced = sorted(p.parent.name for p in tmp_path.glob("host*/*/log.txt"))
    assert produced == names                                  # outputs stay on the worker's side

    status = run_cli(["status", "--store", store_url], tmp_path, env)
    assert "passed     23" in status.stdout and "failed     1" in status.stdout, status.stdout

    report = run_cli(["report", "--store", store_url, "-o", "merged/test.xml"], tmp_path, env)
    assert report.returncode == 1, report.stdout + report.stderr      # one job failed
    root = ET.parse(tmp_path / "merged" / "test.xml").getroot()
    assert [s.get("name") for s in root.iter("testsuite")] == names
    assert (root.get("tests"), root.get("failures")) == ("24", "1")

    start = time.monotonic()
    late = run_cli(["worker", "--store", store_url], tmp_path, env)
    assert late.returncode == 0 and "nothing to do" in late.stdout
    assert time.monotonic() - start < 10


@pytest.mark.slow
def test_killed_worker_jobs_are_reclaimed_after_lease_expiry(store_url, tmp_path):
    env = cli_env(tmp_path)
    names = [f"k{i:02d}" for i in range(12)]
    # The victim claims the first three (long, so it dies while they run); the survivor takes the rest.
    _enqueue(tmp_path, store_url, {n: "sleep=1.5" if n < "k03" else "sleep=0.3" for n in names}, env)
    # The victim claims as if on another host, so only lease expiry can free its jobs.
    victim = start_cli(["worker", "--store", store_url, "-j", "3", "--lease", "3", "--poll", "0.1"],
                       tmp_path, {**env, "SCENARIO_WORKER_HOST": "lost-host"})
    store = QueueStore.open(store_url)
    try:
        deadline = time.monotonic() + 30       # (a loss is charged to a job only once its start is recorded)
        while not any(j.worker_host == "lost-host" and j.child_pid for j in store.running()):
            assert time.monotonic() < deadline and victim.poll() is None
            time.sleep(0.02)
        survivor = start_cli(["worker", "--store", store_url, "-j", "2", "--lease", "3", "--poll", "0.1"],
                             tmp_path, env)
        victim.kill()
        victim.communicate(timeout=10)
        out = survivor.communicate(timeout=120)[0]
        assert survivor.returncode == 0, out
        batch = store.latest_batch()
        jobs = store.jobs(batch.id)
        assert all(j.status is JobState.PASSED for j in jobs), [(j.name, j.status) for j in jobs]
        lost = [j for j in jobs if any(a["outcome"] == "lost" for a in store.attempts(j.id))]
        assert lost, "the killed worker held jobs that had to be reclaimed"
        assert all(j.attempts == 2 and j.worker_host != "lost-host" for j in lost)
        attempts = {j.name: store.attempts(j.id) for j in jobs}
    finally:
        store.close()
    runs = ledger(tmp_path)
    twice = {n: attempts[n] for n, c in runs.items() if c != 1}
    assert set(runs) == set(names) and not twice, (twice, (tmp_path / "ledger.txt").read_text(), out)


@pytest.mark.slow
def test_worker_survives_connection_loss_without_losing_results(pg_url, tmp_path):
    import psycopg

    env = cli_env(tmp_path)
    names = [f"c{i:02d}" for i in range(30)]
    _enqueue(tmp_path, pg_url, {n: "sleep=0.1" for n in names}, env)
    worker = start_cli(["worker", "--store", pg_url, "-j", "2", "--poll", "0.1"], tmp_path, env)
    database = pg_url.rsplit("/", 1)[1]
    killed = 0
    with psycopg.connect(f"postgresql://postgres@127.0.0.1:5432/{database}", autocommit=True) as admin:
        while worker.poll() is None and sum(ledger(tmp_path).values()) < 25:
            killed += admin.execute("SELECT count(pg_terminate_backend(pid)) FROM pg_stat_activity "
                                    "WHERE datname = current_database() AND pid <> pg_backend_pid()"
                                    ).fetchone()[0]
            time.sleep(0.3)
    out = worker.communicate(timeout=120)[0]
    assert worker.returncode == 0, out
    assert killed >= 2 and "retrying" in out
    assert ledger(tmp_path) == Counter({n: 1 for n in names})
    store = QueueStore.open(pg_url)
    try:
        assert store.counts(store.latest_batch().id)[JobState.PASSED] == 30
    finally:
        store.close()
