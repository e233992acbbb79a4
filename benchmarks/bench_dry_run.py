"""Whole-process ``scenario_execution -n`` (parse + resolve) of ours against the reference, side by side.

Measures the hello-world example (median of several runs) and generated files of N scenarios × 20
actions, to show that our cost grows linearly with file size. The reference is the
``scenario_execution`` 1.8.0 command of a scratch virtualenv (default ``/tmp/refvenv``)::

    python3 -m venv /tmp/refvenv && /tmp/refvenv/bin/pip install scenario_execution==1.8.0
    python benchmarks/bench_dry_run.py [--ref /tmp/refvenv/bin/scenario_execution] [--sizes 10,100,300]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def generated_file(n_scenarios: int, actions: int = 20) -> str:
    """A file of ``n_scenarios`` scenarios, each a serial of ``actions`` log actions."""
    lines = ["import osc.helpers", ""]
    for s in range(n_scenarios):
        lines.append(f"scenario scenario_{s}:")
        lines.append(f"    speed_{s}: float = {s}.5")
        lines.append("    do serial:")
        for a in range(actions):
            lines.append(f'        log("scenario {s} step {a}")')
        lines.append("")
    return "\n".join(lines)


#: Both installs are measured as users run them, with cached bytecode: pip precompiled the reference's
#: site-packages, and our editable checkout gets its cache from the warm-up run.
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def run_time(argv: list[str], repeat: int) -> float:
    """Median wall time of ``argv`` over ``repeat`` runs after one warm-up run (each must succeed)."""
    subprocess.run(argv, capture_output=True, text=True, env=ENV)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        proc = subprocess.run(argv, capture_output=True, text=True, env=ENV)
        times.append(time.perf_counter() - start)
        if proc.returncode != 0:
            raise SystemExit(f"failed: {' '.join(argv)}\n{proc.stdout}{proc.stderr}")
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ours", default=shutil.which("scenario_execution", path=str(Path(sys.executable).parent))
                        or "scenario_execution")
    parser.add_argument("--ref", default="/tmp/refvenv/bin/scenario_execution")
    parser.add_argument("--sizes", default="10,100,300")
    parser.add_argument("--repeat", type=int, default=9)
    args = parser.parse_args()
    if not Path(args.ref).exists():
        raise SystemExit(f"reference not found at {args.ref} (see this script's docstring)")
    hello = ROOT / "examples" / "hello_world" / "hello_world.osc"
    python_start = run_time([sys.executable, "-c", "pass"], args.repeat)
    ours = run_time([args.ours, "-n", str(hello)], args.repeat)
    ref = run_time([args.ref, "-n", str(hello)], args.repeat)
    print(f"python start-up                : {python_start * 1000:7.1f} ms")
    print(f"hello world -n  ours {ours:6.3f} s   reference {ref:6.3f} s   ratio {ours / ref:5.3f} (goal <= 0.2)")
    with tempfile.TemporaryDirectory() as tmp:
        for n in [int(x) for x in args.sizes.split(",") if x]:
            path = Path(tmp) / f"gen_{n}.osc"
            path.write_text(generated_file(n), encoding="utf-8")
            ours_n = run_time([args.ours, "-n", str(path)], 3)
            ref_n = run_time([args.ref, "-n", str(path)], 1)
            print(f"N={n:4d} scenarios x 20 actions  ours {ours_n:6.3f} s   reference {ref_n:7.3f} s   "
                  f"ratio {ours_n / ref_n:6.4f}")


if __name__ == "__main__":
    main()
