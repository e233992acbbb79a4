"""The adaptive strategies of ``scenario_variation --from`` against the designs they replace, on the braking
scenario (``examples/search/brake.osc``): the car fails to stop when ``speed² / (2·decel) + speed·reaction > gap``.

Side by side, in one run, 10 seeds each, medians (issue 35's goals in brackets):

* **boundary vs a full grid** (≤ 0.2x): runs until ``boundary`` has located where pass turns to fail to 1 %
  of the speed range (its own ``done``: the gap between the last passing and the first failing speed at most
  1 %), against the 101 runs a grid of 1 % steps needs for the same. One range (decel fixed at 4 m/s²),
  a first round of ``--strategy lhs --samples 4``, then rounds of 4.
* **boundary vs random sampling at the same budget** (≤ 0.5x): the error of the boundary estimate (half the
  gap that holds it, in fractions of the range) after as many random runs as ``boundary`` used; and with
  two ranges (speed and decel), after 60 runs (lhs 20, then 4 rounds of 10), the share of the square on
  the wrong side of the boundary the runs show (a 100 x 100 grid read by the quadratic surface fitted to
  the runs' verdicts, :mod:`coverage_engine.search.surface`, fitted the same way to both designs' runs; read
  by the nearest run instead, the two designs are alike, 4 % and 5 %: ``boundary``'s runs crowd the
  boundary where it was found, and a nearest-run reading cannot draw a curve through them).
* **falsify vs random: runs to the first failure** (≤ 0.3x): only a corner fails (gap 125 m, speed 10..30
  m/s, decel 4..10 m/s², about 0.6 % of the space). ``falsify --objective min_gap`` (Optuna TPE) after a
  first round of ``lhs --samples 8``, in rounds of 8, against uniform random draws; a run's place inside
  its round counts (the runs before the first failing one).

To keep it fast the search comparisons evaluate the braking arithmetic in-process, where the batch would
run the scenario (the proposal code is the command's own: :func:`coverage_engine.search.propose.propose_round`
over a :class:`~coverage_engine.search.history.History` of the runs so far). Then one real round end to
end: ``scenario_variation --strategy lhs`` + ``scenario_batch_execution`` + ``scenario_variation --from
--strategy boundary``, with its printed estimate and wall time.

    python benchmarks/bench_search.py [--seeds 10]
"""

from __future__ import annotations

import argparse
import math
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from coverage_engine.domains import InputDomain
from coverage_engine.search.history import History, PastRun
from coverage_engine.search.propose import SearchOptions, propose_round
from coverage_engine.search.space import Point, Space
from coverage_engine.search.surface import fit_surface
from coverage_engine.search.target import SearchTarget
from coverage_engine.variation.design import unit_columns

BIN = Path(sys.executable).parent
EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "search" / "brake.osc"
REACTION = 1.0
RESOLUTION = 0.01
MAX_ROUNDS = 60


def stopping(speed: float, decel: float) -> float:
    return speed * speed / (2 * decel) + speed * REACTION


class Braking:
    """The scenario's arithmetic over a space of speed (and decel) ranges, as the batch would run it."""

    def __init__(self, speed: tuple[float, float], decel: tuple[float, float] | None, gap: float) -> None:
        axes = [InputDomain("brake.speed", low=speed[0], high=speed[1])]
        if decel is not None:
            axes.append(InputDomain("brake.decel", low=decel[0], high=decel[1]))
        self.space = Space(tuple(axes))
        self.decel, self.gap = decel, gap

    def run(self, point: Point, number: int, round_number: int) -> PastRun:
        assignment = {axis.key: self.space.value_at(i, u) for i, (axis, u) in enumerate(zip(self.space.axes, point,
                                                                                           strict=True))}
        speed = float(assignment["brake.speed"])  # type: ignore[arg-type]
        decel = float(assignment.get("brake.decel", 4.0))  # type: ignore[arg-type]
        margin = self.gap - stopping(speed, decel)
        return PastRun(f"brake{number}", "failed" if margin < 0 else "passed", assignment, {"min_gap": (margin,)},
                       round=round_number)


def search(scenario: Braking, strategy: str, first: int, per_round: int, seed: int,
           stop: Callable[[list[PastRun], object], bool], objective: str | None = None) -> tuple[list[PastRun], object]:
    """Round 1 by lhs, then rounds of ``strategy`` until ``stop(runs, record)``; the runs and the last record."""
    columns = unit_columns("lhs", first, len(scenario.space.axes), seed)
    runs = [scenario.run(tuple(p), i, 1) for i, p in enumerate(zip(*columns, strict=True))]
    record = None
    for number in range(2, MAX_ROUNDS + 2):
        options = SearchOptions(strategy, per_round, seed * 1000 + number, (),
                                SearchTarget(objective=objective, resolution=RESOLUTION))
        proposal = propose_round(scenario.space, History(tuple(runs)), options)
        record = proposal.record
        if stop(runs, record) or not proposal.points:
            break
        runs += [scenario.run(p, len(runs) + i, number) for i, p in enumerate(proposal.points)]
    return runs, record


def flip_error(runs: list[PastRun]) -> float:
    """Half the gap between the fastest passing and the slowest failing speed above it (fraction of the range)."""
    points = sorted((float(r.assignment["brake.speed"]), r.failed) for r in runs)  # type: ignore[arg-type]
    flips = [(a, b) for (a, fa), (b, fb) in zip(points, points[1:], strict=False) if fa != fb]
    if not flips:
        return 0.5
    a, b = flips[0]
    return (b - a) / 2 / 30.0


def boundary_side_by_side(seeds: int) -> None:
    one = Braking((10.0, 40.0), None, 80.0)
    truth = -REACTION * 4.0 + math.sqrt((REACTION * 4.0) ** 2 + 2 * 4.0 * 80.0)
    used, errors, random_errors = [], [], []
    for seed in range(seeds):
        runs, record = search(one, "boundary", 4, 4, seed, lambda runs, rec: rec.estimate.done)
        axis = record.estimate.boundary.axes["brake.speed"]
        assert abs(axis.value - truth) <= axis.error + 1e-9, (axis, truth)
        used.append(len(runs))
        errors.append(axis.error / 30.0)
        rng = random.Random(seed)
        sample = [one.run((rng.random(),), i, 1) for i in range(len(runs))]
        random_errors.append(flip_error(sample))
    grid = round(1 / RESOLUTION) + 1
    runs_median = statistics.median(used)
    print(f"boundary to 1 % (one range, {seeds} seeds): median {runs_median:g} runs (min {min(used)}, max {max(used)}) "
          f"vs a grid of 1 % steps: {grid} runs -> {runs_median / grid:.2f}x (goal <= 0.2x)")
    ours, theirs = statistics.median(errors), statistics.median(random_errors)
    print(f"boundary error at equal budget: boundary {ours * 100:.2f} % of the range vs random {theirs * 100:.2f} % "
          f"-> {ours / theirs:.2f}x (goal <= 0.5x)")


def misclassified(scenario: Braking, runs: list[PastRun]) -> float:
    """How much of the square the runs get wrong: the share of a 100 x 100 grid on the wrong side of the
    boundary the runs show (the quadratic surface ``boundary`` fits to the runs' verdicts, fitted the same
    way to either design's runs)."""
    points = [scenario.space.point_of(run.assignment) for run in runs]
    surface = fit_surface([p for p in points if p is not None], [r.failed for r, p in zip(runs, points, strict=True)
                                                                  if p is not None])
    if surface is None:
        return 1.0
    wrong = 0
    for i in range(100):
        for j in range(100):
            u = ((i + 0.5) / 100, (j + 0.5) / 100)
            wrong += (surface.score(u) > 0) != scenario.run(u, 0, 1).failed
    return wrong / 10_000


def surface_side_by_side(seeds: int) -> None:
    two = Braking((10.0, 40.0), (2.0, 10.0), 80.0)
    ours, theirs, budget = [], [], 0
    for seed in range(seeds):
        runs, _ = search(two, "boundary", 20, 10, seed, lambda runs, rec: len(runs) >= 60)
        budget = len(runs)
        ours.append(misclassified(two, runs))
        rng = random.Random(seed)
        theirs.append(misclassified(two, [two.run((rng.random(), rng.random()), i, 1) for i in range(budget)]))
    a, b = statistics.median(ours), statistics.median(theirs)
    print(f"boundary of two ranges at {budget} runs (lhs 20 + 4 rounds of 10): share of the square on the wrong "
          f"side of the boundary fitted to the runs, boundary {a * 100:.2f} % vs random {b * 100:.2f} % -> {a / b:.2f}x "
          "(goal <= 0.5x)")


def first_failure(runs: list[PastRun]) -> int | None:
    return next((i + 1 for i, run in enumerate(runs) if run.failed), None)


def falsify_side_by_side(seeds: int) -> None:
    corner = Braking((10.0, 30.0), (4.0, 10.0), 125.0)
    ours, theirs = [], []
    for seed in range(seeds):
        runs, _ = search(corner, "falsify", 8, 8, seed, lambda runs, rec: any(r.failed for r in runs),
                         objective="min_gap")
        found = first_failure(runs)
        ours.append(found if found is not None else math.inf)
        rng = random.Random(seed)
        count = 0
        while True:
            count += 1
            if corner.run((rng.random(), rng.random()), count, 1).failed:
                break
        theirs.append(count)
    a, b = statistics.median(ours), statistics.median(theirs)
    print(f"runs to the first failure ({seeds} seeds): falsify median {a:g} (runs {sorted(ours)}) vs random "
          f"median {b:g} -> {a / b:.2f}x (goal <= 0.3x)")


def end_to_end() -> None:
    """One real round: lhs, the batch, then boundary from its results, through the console scripts."""
    env = dict(os.environ, NO_COLOR="1")
    env.pop("SCENARIO_STORE", None)
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        start = time.perf_counter()
        steps = [["scenario_variation", str(EXAMPLE), "--strategy", "lhs", "--samples", "16", "--seed", "1",
                  "-o", "round1"],
                 ["scenario_batch_execution", "-i", "round1", "-o", "results1"],
                 ["scenario_variation", str(EXAMPLE), "--from", "results1", "--strategy", "boundary", "--samples", "8",
                  "--seed", "2", "-o", "round2"]]
        out = ""
        for argv in steps:
            done = subprocess.run([str(BIN / argv[0]), *argv[1:]], cwd=work, env=env, capture_output=True, text=True)
            if done.returncode not in (0, 1):
                raise SystemExit(f"{' '.join(argv)} failed:\n{done.stdout}{done.stderr}")
            out = done.stdout
        took = time.perf_counter() - start
        estimate = [line for line in out.splitlines() if line.startswith(("round ", "boundary", "goal"))]
        written = len(list((work / "round2").glob("*.sce")))
        print(f"end to end (lhs 16 -> batch -> boundary 8): {took:.1f} s, {written} variants proposed, "
              f"search.json {'written' if (work / 'round2' / 'search.json').is_file() else 'MISSING'}; "
              + " | ".join(estimate))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=10)
    args = parser.parse_args()
    boundary_side_by_side(args.seeds)
    surface_side_by_side(args.seeds)
    falsify_side_by_side(args.seeds)
    end_to_end()


if __name__ == "__main__":
    main()
