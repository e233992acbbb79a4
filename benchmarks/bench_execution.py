"""Execution speed, side by side with the reference ``scenario_execution`` 1.8.0.

Two figures, each for our command and the reference's, in the same run:

1. **trivial run** — whole-process wall time of ``scenario_execution trivial.osc`` where the scenario
   is ``log`` then ``emit end`` (median of several runs). Goal: ours ≤ 0.3 × the reference.
2. **step-based throughput** — ``wait elapsed(10s)`` under ``--simulation`` with ``dt = 1 ms``
   (10 000 steps); steps per second over the wall time from the first to the last ``step()`` call,
   measured inside the simulation (so start-up and parsing are excluded). Goal: ours ≥ 10 × the
   reference.

Usage::

    python benchmarks/bench_execution.py [--ours CMD] [--reference CMD] [--runs N]

The reference defaults to ``/tmp/refvenv/bin/scenario_execution``; create it with
``python3 -m venv /tmp/refvenv && /tmp/refvenv/bin/pip install scenario_execution==1.8.0``.
If it is missing, only our figures are printed.
"""

from __future__ import annotations

import argparse
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REFERENCE = "/tmp/refvenv/bin/scenario_execution"

TRIVIAL = """import osc.helpers

scenario trivial:
    do serial:
        log("hello")
        emit end
"""

STEPPED = """import osc.helpers

scenario stepped:
    do serial:
        wait elapsed(10s)
        emit end
"""

SIMULATION = '''
try:  # the reference exports its base class; ours is duck-typed the same way
    from scenario_execution import SimulationInterface as Base
except ImportError:
    Base = object


import time


class BenchSim(Base):
    """dt = 1 ms, nothing to compute: measures the runner's own cost per step.

    The wall time from the first to the last step() is the runner's loop, without start-up and
    parsing, so both implementations are measured on the same stretch.
    """

    def __init__(self):
        self.steps = 0
        self.first = self.last = None

    @property
    def dt(self):
        return 0.001

    def setup(self, **kwargs):
        pass

    def reset(self, **kwargs):
        self.steps = 0

    def step(self):
        now = time.perf_counter()
        if self.first is None:
            self.first = now
        self.last = now
        self.steps += 1

    def shutdown(self):
        print(f"BENCH steps={self.steps} seconds={self.last - self.first:.6f}", flush=True)
'''


def _default_ours() -> str:
    here = Path(sys.executable).parent / "scenario_execution"
    return str(here) if here.exists() else (shutil.which("scenario_execution") or "scenario_execution")


def timed(argv: list[str], cwd: Path) -> tuple[float, str]:
    """Wall time and output of one run; raises if the command fails."""
    env = dict(os.environ, PYTHONPATH=str(cwd))
    # Measure both installs as users run them, with cached bytecode (pip precompiles the reference's
    # site-packages; ours is an editable checkout whose cache the first run writes).
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    start = time.perf_counter()
    done = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{shlex.join(argv)} failed ({done.returncode}):\n{done.stdout}\n{done.stderr}")
    return elapsed, done.stdout + done.stderr


def steps_per_second(output: str) -> float:
    """From the simulation's ``BENCH steps=N seconds=S`` line."""
    for line in output.splitlines():
        if line.startswith("BENCH "):
            fields = dict(part.split("=") for part in line.split()[1:])
            return (int(fields["steps"]) - 1) / max(float(fields["seconds"]), 1e-9)
    raise RuntimeError(f"no BENCH line in:\n{output}")


def measure(command: str, work: Path, runs: int) -> dict[str, float]:
    """Median trivial-run time and step throughput of one ``scenario_execution`` command."""
    base = shlex.split(command)
    timed(base + ["trivial.osc"], work)  # warm the file cache
    trivial = statistics.median(timed(base + ["trivial.osc"], work)[0] for _ in range(runs))
    rates = [steps_per_second(timed(base + ["stepped.osc", "--simulation", "bench_sim:BenchSim"], work)[1])
             for _ in range(max(1, runs // 3))]
    return {"trivial_s": trivial, "steps_per_s": statistics.median(rates)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ours", default=_default_ours())
    parser.add_argument("--reference", default=REFERENCE)
    parser.add_argument("--runs", type=int, default=9)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench_execution_") as tmp:
        work = Path(tmp)
        (work / "trivial.osc").write_text(TRIVIAL)
        (work / "stepped.osc").write_text(STEPPED)
        (work / "bench_sim.py").write_text(SIMULATION)
        ours = measure(args.ours, work, args.runs)
        reference = None
        if Path(args.reference).exists() or shutil.which(args.reference):
            reference = measure(args.reference, work, args.runs)
    print(f"{'':32}{'ours':>12}{'reference':>14}{'ratio':>10}")
    ref_trivial = f"{reference['trivial_s'] * 1000:11.0f} ms" if reference else f"{'-':>14}"
    ratio = f"{ours['trivial_s'] / reference['trivial_s']:9.2f}x" if reference else ""
    print(f"{'trivial run (log, emit end)':32}{ours['trivial_s'] * 1000:9.0f} ms{ref_trivial}{ratio}"
          "   (goal <= 0.30x)")
    ref_steps = f"{reference['steps_per_s']:14.0f}" if reference else f"{'-':>14}"
    ratio = f"{ours['steps_per_s'] / reference['steps_per_s']:9.1f}x" if reference else ""
    print(f"{'steps/s, wait elapsed(10s) dt=1ms':32}{ours['steps_per_s']:12.0f}{ref_steps}{ratio}"
          "   (goal >= 10x)")
    if reference is None:
        print(f"(reference not found at {args.reference}: python3 -m venv /tmp/refvenv && "
              "/tmp/refvenv/bin/pip install scenario_execution==1.8.0)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
