"""What collecting cover()/record() samples costs a step-based run: 10^5 ticks with and without items.

All runs are the same scenario stepped by a do-nothing simulation (``dt`` 0.01 s) for ``--ticks``
ticks: a ``repeat`` of ``increment(count)`` and ``emit step``. Measured side by side against the run
without items:

* ``at end``: four items (a range cover, an enum-like bool cover, their cross, a record) sampled at
  the end of the run and at ``finish``, the usual case (goal: under 2 % more wall time);
* ``every tick``: the same items sampled on every ``step`` event (3 x 10^5 samples and a 3 MB
  ``coverage.json``), the worst case.

Rounds alternate (baseline, measured, ...) and the medians are compared.

    python benchmarks/bench_coverage_sampling.py [--ticks 100000] [--rounds 3]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIN = Path(sys.executable).parent
SIMULATION = "class Stepper:\n    dt = 0.01\n\n    def step(self):\n        pass\n"
SCENARIO = """import osc.helpers

enum parity: [even, odd]

scenario ticks:
    var count: int = 0
    event step
{items}    do serial:
        serial:
            repeat({ticks})
            increment(count)
            emit step
"""
ITEMS = """    cover(count_seen, expression: count, event: {event}, range: [0..{ticks}], every: {width})
    cover(parity_x_count, items: [count_seen, odd], event: {event})
    cover(odd, expression: count % 2 == 1, event: {event})
    record(last_count, expression: count, event: finish)
"""


def run(folder: Path, name: str) -> float:
    start = time.perf_counter()
    done = subprocess.run([str(BIN / "scenario_execution"), f"{name}.osc", "-o", f"out_{name}",
                           "--simulation", "stepper.py:Stepper"], cwd=folder, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(done.stdout + done.stderr)
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=100_000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "stepper.py").write_text(SIMULATION)
        (folder / "plain.osc").write_text(SCENARIO.format(items="", ticks=args.ticks))
        width = max(1, args.ticks // 10)
        (folder / "at_end.osc").write_text(SCENARIO.format(
            items=ITEMS.format(ticks=args.ticks, width=width, event="end"), ticks=args.ticks))
        (folder / "every_tick.osc").write_text(SCENARIO.format(
            items=ITEMS.format(ticks=args.ticks, width=width, event="step"), ticks=args.ticks))
        times: dict[str, list[float]] = {"plain": [], "at_end": [], "every_tick": []}
        for _ in range(args.rounds):
            for name in times:
                times[name].append(run(folder, name))
        base = statistics.median(times["plain"])
        print(f"{args.ticks} ticks, {args.rounds} rounds (medians): without items {base:.2f} s")
        for name, goal in (("at_end", " (goal < 2 %)"), ("every_tick", "")):
            measured = statistics.median(times[name])
            size = (folder / f"out_{name}" / "coverage.json").stat().st_size
            print(f"items sampled {name.replace('_', ' ')}: {measured:.2f} s, overhead "
                  f"{100 * (measured / base - 1):+.1f} %{goal}; coverage.json {size / 1e6:.2f} MB")


if __name__ == "__main__":
    main()
