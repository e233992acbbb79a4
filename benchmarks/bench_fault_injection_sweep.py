"""The full 64-variant fault-injection sweep of the navigation tutorial, end to end, and its pass-rate grid.

scenario_variation expands examples/navigation/test_fault_injection.osc (laser noise 0.0..0.7 m x
random beam drops 0..70 %, the reference coverage package's file unchanged) into 64 .sce files;
scenario_batch_execution runs them with -j 2, each step-based on the PyBullet navigation backend.
Prints the wall time of each stage and the grid of verdicts (rows: noise, columns: drop share)
read from the merged JUnit report's variation properties, plus the pass rate per row and column.
Baseline for the wall time: the same 64 runs one after the other without the batch runner
(--baseline, takes twice as long).

    python benchmarks/bench_fault_injection_sweep.py [-j 2] [--baseline] [--keep DIR]

Once the built-in runner lands, add its flag in BATCH_RUNNER below; once scenario_coverage lands,
its report replaces the grid printed here (the same two input items, crossed, with the verdict).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
SOURCE = ROOT / "examples" / "navigation" / "test_fault_injection.osc"
SIMULATION = "executor.simulations.pybullet:PyBulletSimulation"
BATCH_RUNNER: list[str] = ["--", str(BIN / "scenario_execution"), "{SCENARIO}", "-o", "{OUTPUT_DIR}",
                           "--simulation", SIMULATION]


def timed(argv: list[str], cwd: Path, env: dict) -> tuple[float, subprocess.CompletedProcess]:
    start = time.perf_counter()
    done = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True)
    return time.perf_counter() - start, done


def grid(report: Path) -> dict[tuple[str, str], str]:
    cells = {}
    for suite in ET.parse(report).getroot().iter("testsuite"):
        properties = {p.get("name"): p.get("value") for p in suite.iter("property")}
        noise = properties.get("variation.nav2_simulation_fault_injection.noise.parameter_value", "?")
        drop = properties.get("variation.nav2_simulation_fault_injection.drop.parameter_value", "?")
        cells[(noise.strip("'\""), drop.strip("'\""))] = properties.get("status", "?")
    return cells


def print_grid(cells: dict[tuple[str, str], str]) -> None:
    noises = sorted({n for n, _ in cells}, key=float)
    drops = sorted({d for _, d in cells}, key=float)
    print("noise \\ drop " + " ".join(f"{d:>5}" for d in drops) + "   pass rate")
    for noise in noises:
        row = [cells.get((noise, d), "?") for d in drops]
        marks = " ".join(f"{'pass' if s == 'passed' else 'FAIL':>5}" for s in row)
        print(f"{noise:>12} {marks}   {sum(s == 'passed' for s in row) / len(row):6.0%}")
    column = [sum(cells.get((n, d)) == "passed" for n in noises) / len(noises) for d in drops]
    print(f"{'pass rate':>12} " + " ".join(f"{c:5.0%}" for c in column)
          + f"   {sum(s == 'passed' for s in cells.values()) / len(cells):6.0%} overall")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-j", default="2")
    parser.add_argument("--baseline", action="store_true", help="also run the 64 files one by one, no batch runner")
    parser.add_argument("--keep", help="work in this folder and keep it")
    args = parser.parse_args()
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench_sweep_"))
    work.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, NO_COLOR="1")
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    store = f"sqlite:///{work / 'store.db'}"
    try:
        seconds, done = timed([str(BIN / "scenario_variation"), str(SOURCE), "-o", "in", "--store", store], work, env)
        if done.returncode != 0:
            raise SystemExit(done.stdout + done.stderr)
        print(f"scenario_variation: 64 variants in {seconds:.2f} s")
        seconds, done = timed([str(BIN / "scenario_batch_execution"), "-i", "in", "-o", "results", "-j", args.j,
                               "--store", store, *BATCH_RUNNER], work, env)
        print(f"scenario_batch_execution -j {args.j}: {seconds:.1f} s wall for 64 runs "
              f"({seconds / 64:.2f} s per run, exit code {done.returncode})")
        print_grid(grid(work / "results" / "test.xml"))
        if args.baseline:
            start = time.perf_counter()
            for variant in sorted((work / "in").glob("*.sce")):
                subprocess.run([str(BIN / "scenario_execution"), str(variant), "-o", str(work / "plain" / variant.stem),
                                "--simulation", SIMULATION], cwd=work, env=env, capture_output=True)
            seconds = time.perf_counter() - start
            print(f"baseline, one after the other without the batch runner: {seconds:.1f} s")
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
