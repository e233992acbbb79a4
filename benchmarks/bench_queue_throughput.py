"""Claim-and-finish throughput of no-op jobs with 1, 2 and 4 worker processes, on PostgreSQL and SQLite.

Each worker process runs the store API the way a worker does (claim one job, finish it with a
result) until the queue is empty; no child process is started, so this measures the queue alone.
Printed side by side with the goal of issue 6 (500 jobs/s with 4 workers on PostgreSQL) and with
one worker's rate (the scaling ratio).

    python benchmarks/bench_queue_throughput.py [--jobs 4000] [--pg postgresql://postgres@127.0.0.1:5432/postgres]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
import uuid

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from store.jobs import BatchOptions, JobSpec  # noqa: E402
from store.queue import QueueStore  # noqa: E402

GOAL_PG_4 = 500.0

WORKER = r"""
import sys, time
sys.path.insert(0, sys.argv[3])
from store.jobs import JobResult, WorkerIdentity
from store.queue import QueueStore
from store.states import JobState
store = QueueStore.open(sys.argv[1])
me = WorkerIdentity.current()
go = float(sys.argv[2])
while time.time() < go:
    time.sleep(0.001)
done = 0
while True:
    jobs = store.claim(me, limit=1, shared_only=True)
    if not jobs:
        break
    now = time.time()
    store.finish(jobs[0], JobResult(JobState.PASSED, 0, now, now, junit_xml="<testsuite/>", log_tail=""))
    done += 1
print(done, time.time())
"""


def run(url: str, workers: int, jobs: int) -> float:
    """Jobs per second for ``workers`` processes draining ``jobs`` no-op jobs from a fresh batch."""
    store = QueueStore.open(url)
    store.create_batch(mode="shared", input_dir="/bench", output_dir="/bench", host="bench", command=["x"],
                       options=BatchOptions(),
                       specs=[JobSpec(f"j{i}", f"/bench/j{i}.sce", "0") for i in range(jobs)])
    store.close()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    go = time.time() + 1.5                       # every process is connected before the clock starts
    procs = [subprocess.Popen([sys.executable, "-c", WORKER, url, str(go), root], stdout=subprocess.PIPE,
                              text=True) for _ in range(workers)]
    results = [p.communicate()[0].split() for p in procs]
    if any(p.returncode for p in procs):
        raise SystemExit("a worker failed")
    done = sum(int(r[0]) for r in results)
    end = max(float(r[1]) for r in results)
    assert done == jobs, (done, jobs)
    return jobs / (end - go)


def pg_database(admin_url: str):
    import psycopg

    name = f"bench_queue_{uuid.uuid4().hex[:8]}"
    admin = psycopg.connect(admin_url, autocommit=True)
    admin.execute(f'CREATE DATABASE "{name}"')
    host = admin_url.split("://", 1)[1].rsplit("/", 1)[0]
    return admin, name, f"postgresql+psycopg://{host}/{name}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=4000)
    parser.add_argument("--pg", default="postgresql://postgres@127.0.0.1:5432/postgres",
                        help="admin URL of the PostgreSQL server (a scratch database is created)")
    args = parser.parse_args()
    rows = []
    for engine in ("postgresql", "sqlite"):
        one = None
        for workers in (1, 2, 4):
            if engine == "postgresql":
                admin, name, url = pg_database(args.pg)
                try:
                    rate = run(url, workers, args.jobs)
                finally:
                    admin.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
                    admin.close()
            else:
                with tempfile.TemporaryDirectory() as tmp:
                    rate = run(f"sqlite:///{tmp}/bench.db", workers, args.jobs)
            one = one or rate
            rows.append((engine, workers, rate, rate / one))
    print(f"claim+finish of {args.jobs} no-op jobs (one claim and one finish transaction per job)")
    print(f"{'engine':<11} {'workers':>7} {'jobs/s':>9} {'vs 1 worker':>12} {'goal':>7} {'ratio':>6}")
    for engine, workers, rate, scale in rows:
        goal = GOAL_PG_4 if (engine, workers) == ("postgresql", 4) else None
        goal_text = f"{goal:.0f}" if goal else "-"
        ratio_text = f"{rate / goal:.2f}" if goal else "-"
        print(f"{engine:<11} {workers:>7} {rate:>9.0f} {scale:>11.2f}x {goal_text:>7} {ratio_text:>6}")


if __name__ == "__main__":
    main()
