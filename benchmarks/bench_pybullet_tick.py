"""example_pybullet.osc step-based against the wall-clock tick, in one run: simulated seconds per wall second.

The reference's example (a Husky driven 2 m on a plane) runs three ways: with the wall-clock tick
at -s 1/240 s (the reference README's setting) and at -s 0.05 s, and step-based with
--simulation executor.simulations.pybullet:PyBulletSimulation. The simulated time comes from a
copy of the example that stores and logs the world's time when the 2 m are reached (the physics
is the same); the wall time is the scenario's own duration from test.xml (process start-up apart).

    python benchmarks/bench_pybullet_tick.py [--rounds 3]
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
EXAMPLE = ROOT / "examples" / "pybullet" / "example_pybullet.osc"
MODES = {
    "wall-clock tick, -s 1/240 s": ["-s", str(1 / 240)],
    "wall-clock tick, -s 0.05 s": ["-s", "0.05"],
    "step-based (PyBulletSimulation)": ["--simulation", "executor.simulations.pybullet:PyBulletSimulation"],
}


def measuring_copy(folder: Path) -> Path:
    text = EXAMPLE.read_text(encoding="utf-8")
    text = text.replace("    actor1: actor_pybullet\n", "    actor1: actor_pybullet\n    var t: time = 0s\n")
    text = text.replace("                emit end", "                sim.store_time(t)\n                log(t)\n"
                        "                emit end")
    path = folder / "example_pybullet_timed.osc"
    path.write_text(text, encoding="utf-8")
    return path


def run(scenario: Path, options: list[str], folder: Path, env: dict) -> tuple[float, float]:
    out = folder / "out"
    done = subprocess.run([str(BIN / "scenario_execution"), str(scenario), "-o", str(out), *options],
                          cwd=folder, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(done.stdout + done.stderr)
    simulated = float(re.findall(r"\[log\] ([0-9.]+)", done.stdout)[-1])
    wall = float(next(ET.parse(out / "test.xml").getroot().iter("testcase")).get("time"))
    return simulated, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    env = dict(os.environ, NO_COLOR="1")
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        scenario = measuring_copy(folder)
        results = {}
        for name, options in MODES.items():
            best = None
            for _ in range(args.rounds):
                simulated, wall = run(scenario, options, folder, env)
                if best is None or wall < best[1]:
                    best = (simulated, wall)
            results[name] = best
            print(f"{name:34} {best[0]:6.2f} s simulated in {best[1]:6.2f} s wall: "
                  f"{best[0] / best[1]:7.1f} simulated s per wall s")
        step = results["step-based (PyBulletSimulation)"]
        tick = results["wall-clock tick, -s 1/240 s"]
        print(f"step-based / wall-clock tick (1/240 s): {(step[0] / step[1]) / (tick[0] / tick[1]):.1f}x")


if __name__ == "__main__":
    main()
