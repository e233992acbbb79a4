"""``scenario_coverage report`` and ``html`` over 100,000 stored runs with 20 items each.

A SQLite store gets one batch of N jobs (passed / failed / error, three varied parameters in the
variant assignment) and, per job, a coverage row of 20 items — 10 ranged or distinct numeric cover
items, 3 enum/bool cover items, 3 crosses and 4 records, one sample each — recorded through
``store.coverage_records`` the way the batch runner records it. Then the real command runs as a child
process, timed, its peak RSS taken from ``wait4``:

* ``scenario_coverage report --store URL -o report.txt``
* ``scenario_coverage html --store URL -o coverage.html``

Side by side with the baseline **"read only"**: a child that reads the same rows (the job columns and
the coverage body, in the same chunks) and decodes each body's JSON, doing nothing with them — the
floor any report from the store pays. The ratio is ours / baseline. Goals (issue 13): under 5 s and
under 300 MB each.

    python benchmarks/bench_coverage_report.py [--runs 100000] [--keep DIR]
"""

from __future__ import annotations

import argparse
import os
import random
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from sqlalchemy import update  # noqa: E402

from store.coverage_records import CoverageRecords  # noqa: E402
from store.jobs import BatchOptions, JobSpec  # noqa: E402
from store.queue import QueueStore  # noqa: E402
from store.queue_tables import jobs  # noqa: E402

GOAL_SECONDS = 5.0
GOAL_MB = 300.0

BASELINE = r"""
import json, sys
sys.path.insert(0, sys.argv[2])
from store.coverage_records import CoverageRecords
records = CoverageRecords.open(sys.argv[1])
n = 0
for row in records.iter_batch(1):
    if row.body is not None:
        json.loads(row.body)
    n += 1
print(n)
"""

ENUM_MEMBERS = ["left", "right", "center", "merge"]


def _items() -> list[dict]:
    items = []
    for i in range(10):
        item = {"name": f"kpi{i}", "kind": "cover", "path": "cut_in", "type": "float" if i % 2 else "int",
                "unit": "m/s" if i % 2 else None, "event": "end"}
        if i < 8:
            item.update(range=[0, 100], every=10 if i % 2 else 20)
        items.append(item)
    items.append({"name": "side", "kind": "cover", "path": "cut_in", "type": "enum", "members": ENUM_MEMBERS})
    items.append({"name": "braked", "kind": "cover", "path": "cut_in", "type": "bool"})
    items.append({"name": "weather", "kind": "cover", "path": "cut_in", "type": "enum",
                  "members": ["dry", "wet", "snow"]})
    items.append({"name": "kpi1_x_side", "kind": "cover", "path": "cut_in", "items": ["kpi1", "side"]})
    items.append({"name": "kpi3_x_braked", "kind": "cover", "path": "cut_in", "items": ["kpi3", "braked"]})
    items.append({"name": "side_x_weather", "kind": "cover", "path": "cut_in", "items": ["side", "weather"]})
    for name in ("min_ttc", "max_decel", "min_gap", "duration"):
        items.append({"name": name, "kind": "record", "path": "cut_in", "type": "float", "unit": "s",
                      "event": "finish"})
    return items


def _document(rng: random.Random, index: int, items: list[dict], verdict: str, assignment: dict) -> dict:
    values: dict[str, object] = {}
    out = []
    for item in items:
        if "items" in item:
            sample = [values[name] for name in item["items"]]
        elif item["type"] == "enum":
            sample = rng.choice(item["members"])
        elif item["type"] == "bool":
            sample = rng.random() < 0.5
        elif item["type"] == "int":
            sample = rng.randrange(0, 100) if "range" in item else rng.randrange(0, 40)
        else:
            sample = round(rng.uniform(0, 100 if item["kind"] == "cover" else 10), 3)
        values[item["name"]] = sample
        out.append({**item, "samples": [sample]})
    return {"format": "scenario-coverage/run", "format_version": 1,
            "run": {"scenario": "cut_in", "variant": f"cut_in{index}", "verdict": verdict, "assignment": assignment},
            "items": out}


def build_store(url: str, runs: int) -> None:
    rng = random.Random(13)
    queue = QueueStore.open(url)
    queue.create_batch(mode="local", input_dir="/bench/out", output_dir="/bench/results", host="bench",
                       command=["x", "{SCENARIO}", "{OUTPUT_DIR}"], options=BatchOptions(),
                       specs=[JobSpec(f"cut_in{i}", f"/bench/out/cut_in{i}.sce", "0") for i in range(runs)])
    verdicts = [rng.choices(["passed", "failed", "error"], weights=[85, 12, 3])[0] for _ in range(runs)]
    with queue.engine.begin() as conn:
        for status in ("passed", "failed", "error"):
            conn.execute(update(jobs).where(jobs.c.seq.in_([i for i, v in enumerate(verdicts) if v == status]))
                         .values(status=status, reason=None if status == "passed" else f"{status} (exit code 1)",
                                 output_dir=None))
        ids = [row[0] for row in conn.execute(jobs.select().with_only_columns(jobs.c.id).order_by(jobs.c.seq))]
    queue.close()
    records = CoverageRecords.open(url)
    items = _items()
    speeds, gaps, sides = [10.0, 20.0, 30.0, 40.0], [5, 10, 15], ["side!left", "side!right"]
    chunk = []
    for i, job_id in enumerate(ids):
        assignment = {"cut_in.speed": speeds[i % 4], "cut_in.gap": gaps[(i // 4) % 3], "cut_in.lane": sides[i % 2]}
        verdict = verdicts[i] if verdicts[i] != "error" else "error"
        chunk.append((job_id, 1, _document(rng, i, items, verdict, assignment)))
        if len(chunk) == 5000:
            records.record_many(chunk)
            chunk = []
    if chunk:
        records.record_many(chunk)
    records.close()


def measure(argv: list[str], cwd: str) -> tuple[float, float, float, str]:
    """Wall seconds, CPU seconds (user + system) and peak RSS (MB) of one child process."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    start = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    _, status, usage = os.wait4(proc.pid, 0)
    seconds = time.perf_counter() - start
    output = proc.stdout.read() if proc.stdout else ""
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed ({proc.returncode}):\n{output}")
    return seconds, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024, output


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=100_000)
    parser.add_argument("--keep", help="Build the store in this folder and keep it (reused when it exists).")
    parser.add_argument("--repeat", type=int, default=2, help="Best of N runs of each command.")
    parser.add_argument("--build", metavar="URL", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.build:
        build_store(args.build, args.runs)
        return
    folder = args.keep or tempfile.mkdtemp(prefix="bench_coverage_")
    os.makedirs(folder, exist_ok=True)
    db = os.path.join(folder, f"store{args.runs}.db")
    url = f"sqlite:///{db}"
    if not os.path.exists(db):
        # Built in a child process: on Linux a child's peak RSS starts from its parent's, so the
        # measuring process must stay small.
        started = time.perf_counter()
        subprocess.run([sys.executable, os.path.abspath(__file__), "--build", url, "--runs", str(args.runs)],
                       check=True)
        print(f"store with {args.runs} runs x 20 items built in {time.perf_counter() - started:.1f} s "
              f"({os.path.getsize(db) / 1e6:.0f} MB)")
    bindir = os.path.dirname(sys.executable)
    command = os.path.join(bindir, "scenario_coverage")
    cases = [
        ("read only (baseline)", [sys.executable, "-c", BASELINE, url, ROOT]),
        ("scenario_coverage report", [command, "report", "--store", url, "-o", os.path.join(folder, "report.txt")]),
        ("scenario_coverage html", [command, "html", "--store", url, "-o", os.path.join(folder, "coverage.html")]),
        ("scenario_coverage json", [command, "json", "--store", url, "-o", os.path.join(folder, "coverage.json")]),
    ]
    results = {}
    for name, argv in cases:
        best = min((measure(argv, folder) for _ in range(args.repeat)), key=lambda r: r[0])
        results[name] = best
    base = results["read only (baseline)"][0]
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs (wall time suffers when other work runs)")
    print(f"{'':28} {'wall s':>8} {'CPU s':>8} {'peak MB':>8} {'x baseline':>10}  goal (wall)")
    for name, (seconds, cpu, mb, _) in results.items():
        goal = "" if name.startswith("read") or name.endswith("json") else (
            "ok" if seconds < GOAL_SECONDS and mb < GOAL_MB else f"MISSED (< {GOAL_SECONDS:g} s, < {GOAL_MB:g} MB)")
        print(f"{name:28} {seconds:8.2f} {cpu:8.2f} {mb:8.0f} {seconds / base:10.2f}  {goal}")
    html = os.path.join(folder, "coverage.html")
    print(f"html report: {os.path.getsize(html) / 1e6:.1f} MB; json: "
          f"{os.path.getsize(os.path.join(folder, 'coverage.json')) / 1e6:.1f} MB")
    if not args.keep:
        import shutil

        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
