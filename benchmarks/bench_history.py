"""``scenario_coverage history`` and ``diff`` over a store of 100 batches x 1,000 runs (issue 36: < 3 s each).

A SQLite store gets B batches of N jobs each, the same N variants every night (same names and contents,
so flakiness is looked up across all batches), verdicts drawn per batch (85 % passed, 12 % failed, 3 %
error), and per job a coverage row of 20 items as :mod:`bench_coverage_report` records them. Each
batch's figures are kept the way the end of a batch keeps them (``record_batch_summary``). Timed, as
child processes, best of ``--repeat``:

* ``scenario_coverage history --store URL``
* ``scenario_coverage history --store URL --json``
* ``scenario_coverage diff 99 100 --store URL --json`` (two batches' verdicts, flakiness over all 100,
  both coverage reports)

Side by side with the baseline ``scenario_coverage report --store URL --batch 100`` (one batch's coverage,
what a nightly job runs anyway). ``--cold`` also times ``history`` on a copy without the kept figures
(every batch's grade computed on the spot).

    python benchmarks/bench_history.py [--batches 100] [--runs 1000] [--keep DIR] [--cold]
"""

from __future__ import annotations

import argparse
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_coverage_report import _document, _items  # noqa: E402
from sqlalchemy import update  # noqa: E402

GOAL_SECONDS = 3.0


def build_store(url: str, batches: int, runs: int) -> None:
    """The store (see the module doc); built in a child so the measuring process stays small."""
    from executor.batch.batch_outcome import batch_outcome
    from executor.batch.history import record_batch_summary
    from store.coverage_records import CoverageRecords
    from store.jobs import BatchOptions, JobSpec
    from store.queue import QueueStore
    from store.queue_tables import jobs

    rng = random.Random(36)
    queue = QueueStore.open(url)
    records = CoverageRecords.attach(queue.engine)
    items = _items()
    speeds, gaps = [10.0, 20.0, 30.0, 40.0], [5, 10, 15]
    specs = [JobSpec(f"cut_in{i}", f"/bench/out/cut_in{i}.sce", f"sha{i}") for i in range(runs)]
    for number in range(batches):
        batch = queue.create_batch(mode="local", input_dir="/bench/out", output_dir=f"/bench/results{number}",
                                   host="bench", command=["x", "{SCENARIO}", "{OUTPUT_DIR}"],
                                   options=BatchOptions(), specs=specs)
        verdicts = [rng.choices(["passed", "failed", "error"], weights=[85, 12, 3])[0] for _ in range(runs)]
        with queue.engine.begin() as conn:
            for status in ("passed", "failed", "error"):
                conn.execute(update(jobs).where(jobs.c.batch_id == batch.id,
                                                jobs.c.seq.in_([i for i, v in enumerate(verdicts) if v == status]))
                             .values(status=status, reason=None if status == "passed" else f"{status} (exit code 1)",
                                     output_dir=None))
            ids = [row[0] for row in conn.execute(jobs.select().with_only_columns(jobs.c.id)
                                                  .where(jobs.c.batch_id == batch.id).order_by(jobs.c.seq))]
        rows = []
        for i, job_id in enumerate(ids):
            assignment = {"cut_in.speed": speeds[i % 4], "cut_in.gap": gaps[(i // 4) % 3]}
            rows.append((job_id, 1, _document(rng, i, items, verdicts[i], assignment)))
        records.record_many(rows)
        outcome = batch_outcome(queue, batch)
        list(outcome.jobs)
        record_batch_summary(queue, batch, outcome)
    queue.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--batches", type=int, default=100)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--keep", help="Build the store in this folder and keep it (reused when it exists).")
    parser.add_argument("--repeat", type=int, default=3, help="Best of N runs of each command.")
    parser.add_argument("--cold", action="store_true", help="Also time history without the kept figures.")
    parser.add_argument("--build", metavar="URL", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.build:
        build_store(args.build, args.batches, args.runs)
        return
    folder = args.keep or tempfile.mkdtemp(prefix="bench_history_")
    os.makedirs(folder, exist_ok=True)
    db = os.path.join(folder, f"history{args.batches}x{args.runs}.db")
    url = f"sqlite:///{db}"
    if not os.path.exists(db):
        started = time.perf_counter()
        subprocess.run([sys.executable, os.path.abspath(__file__), "--build", url, "--batches", str(args.batches),
                        "--runs", str(args.runs)], check=True)
        print(f"store with {args.batches} batches x {args.runs} runs x 20 items built in "
              f"{time.perf_counter() - started:.1f} s ({os.path.getsize(db) / 1e6:.0f} MB)")
    command = os.path.join(os.path.dirname(sys.executable), "scenario_coverage")
    last, before = str(args.batches), str(args.batches - 1)
    cases = [("report --batch LAST (baseline)", [command, "report", "--store", url, "--batch", last, "-o",
                                                 os.path.join(folder, "report.txt")]),
             ("history", [command, "history", "--store", url]),
             ("history --json", [command, "history", "--store", url, "--json"]),
             (f"diff {before} {last} --json", [command, "diff", before, last, "--store", url, "--json"])]
    if args.cold:
        cold = os.path.join(folder, "cold.db")
        shutil.copy(db, cold)
        import sqlite3

        with sqlite3.connect(cold) as conn:
            conn.execute("DELETE FROM batch_summaries")
        cases.append(("history, no kept figures", [command, "history", "--store", f"sqlite:///{cold}"]))
    results = {}
    for name, argv in cases:
        ok_codes = (0, 1) if name.startswith("diff") else (0,)
        results[name] = min((measure_any(argv, folder, ok_codes) for _ in range(args.repeat)), key=lambda r: r[0])
    base = results["report --batch LAST (baseline)"][0]
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs (wall time suffers when other work runs)")
    print(f"{'':32} {'wall s':>8} {'CPU s':>8} {'peak MB':>8} {'x baseline':>10}  goal (< {GOAL_SECONDS:g} s)")
    for name, (seconds, cpu, mb, _) in results.items():
        goal = "" if "baseline" in name or "no kept" in name else ("ok" if seconds < GOAL_SECONDS else "MISSED")
        print(f"{name:32} {seconds:8.2f} {cpu:8.2f} {mb:8.0f} {seconds / base:10.2f}  {goal}")
    if not args.keep:
        shutil.rmtree(folder, ignore_errors=True)


def measure_any(argv: list[str], cwd: str, ok_codes: tuple[int, ...]) -> tuple[float, float, float, str]:
    """Wall seconds, CPU seconds and peak RSS (MB) of one child whose output goes to a file (a diff's JSON
    can pass a pipe's buffer); an exit code outside ``ok_codes`` stops the benchmark."""
    out_path = os.path.join(cwd, "output.txt")
    with open(out_path, "w") as out:
        start = time.perf_counter()
        proc = subprocess.Popen(argv, cwd=cwd, stdout=out, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(proc.pid, 0)
        seconds = time.perf_counter() - start
    code = os.waitstatus_to_exitcode(status)
    with open(out_path) as handle:
        output = handle.read()
    if code not in ok_codes:
        raise SystemExit(f"{' '.join(argv)} failed ({code}):\n{output[-2000:]}")
    return seconds, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024, output


if __name__ == "__main__":
    main()
