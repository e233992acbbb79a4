"""50 variants of the PyBullet drive, end to end: scenario_variation, then scenario_batch_execution.

The drive of examples/pybullet/drive_variation_list.osc over 10 wheel speeds x 5 motor forces
(50 variants; with --strategy lhs, drive_variation.osc --samples 50 is the same size), each run
step-based on PyBullet. Prints the wall time of variation and of the batch (-j 2) with the built-in
runner (``--simulation``, jobs forked from a warm fork server), and as the baseline the same 50 runs
one after the other in a plain loop (no queue, no store, no report).

    python benchmarks/bench_pybullet_batch.py [-j 2]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
SIMULATION = "executor.simulations.pybullet:PyBulletSimulation"
BATCH_RUNNER: list[str] = ["--simulation", SIMULATION]


def fifty_variants(folder: Path) -> Path:
    text = (ROOT / "examples" / "pybullet" / "drive_variation_list.osc").read_text(encoding="utf-8")
    text = text.replace("keep(wheel_speed in [2mps, 5mps, 8mps, 11mps])",
                        "keep(wheel_speed in [" + ", ".join(f"{v}mps" for v in range(2, 12)) + "])")
    text = text.replace("keep(motor_force in [0.1, 0.3, 1.0, 3.0])", "keep(motor_force in [0.1, 0.3, 1.0, 2.0, 4.0])")
    path = folder / "drive_variation_50.osc"
    path.write_text(text, encoding="utf-8")
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-j", default="2")
    args = parser.parse_args()
    env = dict(os.environ, NO_COLOR="1")
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        source = fifty_variants(folder)
        store = f"sqlite:///{folder / 'store.db'}"
        start = time.perf_counter()
        done = subprocess.run([str(BIN / "scenario_variation"), str(source), "-o", "in", "--store", store],
                              cwd=folder, env=env, capture_output=True, text=True)
        variation = time.perf_counter() - start
        if done.returncode != 0:
            raise SystemExit(done.stdout + done.stderr)
        start = time.perf_counter()
        subprocess.run([str(BIN / "scenario_batch_execution"), "-i", "in", "-o", "results", "-j", args.j,
                        "--store", store, *BATCH_RUNNER], cwd=folder, env=env, capture_output=True)
        batch = time.perf_counter() - start
        suites = list(ET.parse(folder / "results" / "test.xml").getroot().iter("testsuite"))
        passed = sum(1 for s in suites for p in s.iter("property") if p.get("name") == "status"
                     and p.get("value") == "passed")
        start = time.perf_counter()
        for variant in sorted((folder / "in").glob("*.sce")):
            subprocess.run([str(BIN / "scenario_execution"), str(variant), "-o", str(folder / "plain" / variant.stem),
                            "--simulation", SIMULATION], cwd=folder, env=env, capture_output=True)
        loop = time.perf_counter() - start
        print(f"scenario_variation: {len(suites)} variants in {variation:.2f} s")
        print(f"scenario_batch_execution -j {args.j}: {batch:.1f} s ({batch / len(suites):.2f} s per variant), "
              f"{passed} of {len(suites)} passed")
        print(f"baseline, a plain loop one after the other: {loop:.1f} s; batch / loop = {batch / loop:.2f}")
        print(f"end to end (variation + batch): {variation + batch:.1f} s")


if __name__ == "__main__":
    main()
