"""Parallel speed-up of scenario_batch_execution: 40 jobs that each sleep 0.5 s, -j 8 against -j 1.

The baseline is our own ``-j 1`` run (the specification runs scenarios one after the other).
Goal (issue 5): ``-j 8`` at least 6x faster.

    python benchmarks/bench_batch_parallel.py [--jobs 40] [--sleep 0.5] [--parallel 8]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIN = Path(sys.executable).parent
JOB = 'sleep {sleep}; echo "<testsuite><testcase name=\\"t\\"/></testsuite>" > "$2/test.xml"'


def run(work: Path, out: str, slots: int, job: str, env: dict[str, str]) -> float:
    start = time.perf_counter()
    result = subprocess.run([str(BIN / "scenario_batch_execution"), "-i", "in", "-o", out, "-j", str(slots),
                             "--", "sh", "-c", job, "sh", "{SCENARIO}", "{OUTPUT_DIR}"],
                            cwd=work, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    elapsed = time.perf_counter() - start
    if result.returncode != 0:
        raise SystemExit(f"batch failed: {result.stderr}")
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=40)
    parser.add_argument("--sleep", type=float, default=0.5)
    parser.add_argument("--parallel", type=int, default=8)
    args = parser.parse_args()
    env = {**os.environ, "NO_COLOR": "1"}
    env.pop("SCENARIO_STORE", None)
    job = JOB.format(sleep=args.sleep)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        (work / "in").mkdir()
        for i in range(args.jobs):
            (work / "in" / f"s{i:03d}.sce").write_text("x\n")
        serial = run(work, "serial", 1, job, env)
        parallel = run(work, "parallel", args.parallel, job, env)
    ideal = args.jobs * args.sleep / args.parallel
    print(f"{args.jobs} jobs of 'sleep {args.sleep}'")
    print(f"{'':<8} {'wall s':>8}")
    print(f"{'-j 1':<8} {serial:>8.2f}")
    print(f"{'-j ' + str(args.parallel):<8} {parallel:>8.2f}   (ideal {ideal:.2f})")
    print(f"speed-up {serial / parallel:.2f}x (goal >= 6x)")


if __name__ == "__main__":
    main()
