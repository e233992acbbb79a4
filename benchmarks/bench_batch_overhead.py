"""Per-job overhead of scenario_batch_execution -j 1 against a bare shell loop running the same commands.

200 jobs whose command sleeps 50 ms and writes a one-testcase test.xml. The baseline is a plain
``sh`` loop that makes each output folder and runs the same command with its output redirected to
log.txt — what a user would write by hand. Ours adds the store (SQLite file: claim, child pid,
result with XML and log tail per job), process groups, and the merged report. Goal (issue 5):
ours at most 1.1x the loop, under 5 ms per job.

    python benchmarks/bench_batch_overhead.py [--jobs 200] [--sleep 0.05] [--rounds 3]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIN = Path(sys.executable).parent
JOB = 'sleep {sleep}; echo "<testsuite><testcase name=\\"t\\"/></testsuite>" > "$2/test.xml"'

LOOP = r'''
for f in "$1"/*.sce; do
  n=$(basename "$f" .sce)
  mkdir -p "$2/$n"
  sh -c "$3" sh "$f" "$2/$n" > "$2/$n/log.txt" 2>&1
done
'''


def timed(argv: list[str], cwd: Path, env: dict[str, str]) -> float:
    start = time.perf_counter()
    result = subprocess.run(argv, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    elapsed = time.perf_counter() - start
    if result.returncode != 0:
        raise SystemExit(f"{argv[0]} failed: {result.stderr}")
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=200)
    parser.add_argument("--sleep", type=float, default=0.05)
    parser.add_argument("--rounds", type=int, default=3, help="runs of each; the best is reported")
    args = parser.parse_args()
    job = JOB.format(sleep=args.sleep)
    env = {**os.environ, "NO_COLOR": "1"}
    env.pop("SCENARIO_STORE", None)
    ours, base = [], []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        (work / "in").mkdir()
        for i in range(args.jobs):
            (work / "in" / f"s{i:04d}.sce").write_text("x\n")
        for round_ in range(args.rounds):
            base.append(timed(["sh", "-c", LOOP, "loop", "in", f"loop{round_}", job], work, env))
            ours.append(timed([str(BIN / "scenario_batch_execution"), "-i", "in", "-o", f"ours{round_}",
                               "--", "sh", "-c", job, "sh", "{SCENARIO}", "{OUTPUT_DIR}"], work, env))
            shutil.rmtree(work / f"loop{round_}")
            shutil.rmtree(work / f"ours{round_}")
    best_ours, best_base = min(ours), min(base)
    print(f"{args.jobs} jobs of 'sleep {args.sleep}' with -j 1, best of {args.rounds}")
    print(f"{'':<26} {'wall s':>8} {'ms/job':>8}")
    print(f"{'bare shell loop':<26} {best_base:>8.2f} {best_base / args.jobs * 1000:>8.1f}")
    print(f"{'scenario_batch_execution':<26} {best_ours:>8.2f} {best_ours / args.jobs * 1000:>8.1f}")
    overhead = (best_ours - best_base) / args.jobs * 1000
    print(f"ratio ours/loop {best_ours / best_base:.3f} (goal <= 1.1); overhead {overhead:.2f} ms/job "
          f"(goal < 5), start-up and merged report included")


if __name__ == "__main__":
    main()
