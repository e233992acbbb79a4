"""``falsify``: drive an objective (a ``record()`` item, or the margin of the ``compare`` checks) towards
failure with Optuna, in ask/tell mode across rounds.

Nothing persists between rounds but the results: each round rebuilds the study from the runs read
(every earlier run with a value becomes a completed trial) and asks it for ``--samples`` new points,
which the batch runs and the next round reads back. The sampler is seeded (the round's seed), so the
same results and seed ask the same points. The sampler is TPE for every space: CMA-ES warm-started from
the earlier runs (Optuna's ``source_trials``) was tried for all-continuous spaces and needed 2 to 20
rounds of 8 to reach the failing corner of the braking scenario where TPE needed 2 or 3 (5 seeds), and a
rebuilt CMA-ES without a warm start would ignore the results altogether.

Axes are the unit cube's: a continuous range is a float in [0, 1]; a listed axis of ``k`` values an
integer ``0..k-1`` (the value's index). Optuna is an optional extra (``scenario-coverage[search]``),
imported only here, only when this strategy runs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from coverage_engine.search.errors import SearchError
from coverage_engine.search.estimate import WorstCase
from coverage_engine.search.history import MARGIN
from coverage_engine.search.space import Point, Space

__all__ = ["MARGIN", "FalsifyProposal", "Scored", "propose_falsify", "worst_case"]

@dataclass(frozen=True)
class Scored:
    """A run where it sits, its objective value, whether it failed, and its assignment."""

    point: Point
    value: float
    failed: bool
    assignment: Mapping[str, object]


@dataclass(frozen=True)
class FalsifyProposal:
    points: tuple[Point, ...]
    worst: WorstCase | None
    done: bool


def _optuna() -> Any:
    try:
        import optuna
    except ImportError:
        raise SearchError("--strategy falsify needs Optuna, which is not installed",
                          hint="install the search extra: pip install 'scenario-coverage[search]'") from None
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna


def _name(axis: int) -> str:
    return f"x{axis}"


def _distributions(optuna: Any, space: Space) -> dict[str, Any]:
    found = {}
    for axis in range(len(space.axes)):
        levels = space.levels(axis)
        found[_name(axis)] = optuna.distributions.FloatDistribution(0.0, 1.0) if levels is None \
            else optuna.distributions.IntDistribution(0, levels - 1)
    return found


def _params(space: Space, point: Point) -> dict[str, float | int]:
    params: dict[str, float | int] = {}
    for axis, u in enumerate(point):
        levels = space.levels(axis)
        params[_name(axis)] = u if levels is None else min(int(u * levels), levels - 1)
    return params


def _point(space: Space, params: Mapping[str, Any]) -> Point:
    coordinates = []
    for axis in range(len(space.axes)):
        levels = space.levels(axis)
        value = params[_name(axis)]
        coordinates.append(float(value) if levels is None else (int(value) + 0.5) / levels)
    return space.snap(coordinates)


def worst_case(scored: Sequence[Scored], objective: str, maximise: bool) -> WorstCase | None:
    """The run whose objective is worst (lowest; highest with ``maximise``); a failing run wins a tie."""
    if not scored:
        return None
    sign = -1.0 if maximise else 1.0
    best = min(scored, key=lambda s: (sign * s.value, not s.failed))
    return WorstCase(objective, best.value, best.assignment, best.failed)


def propose_falsify(space: Space, scored: Sequence[Scored], samples: int, seed: int, objective: str,
                    maximise: bool = False, any_failed: bool = False) -> FalsifyProposal:
    """``samples`` points the optimiser asks for next, the worst case so far, and whether a run failed."""
    optuna = _optuna()
    distributions = _distributions(optuna, space)
    direction = "maximize" if maximise else "minimize"
    trials = [optuna.trial.create_trial(params=_params(space, s.point), distributions=distributions, value=s.value)
              for s in scored if math.isfinite(s.value)]
    study = optuna.create_study(direction=direction, sampler=optuna.samplers.TPESampler(seed=seed))
    study.add_trials(trials)
    points = tuple(_point(space, study.ask(distributions).params) for _ in range(samples))
    worst = worst_case(scored, objective, maximise)
    return FalsifyProposal(points, worst, any_failed or (worst is not None and worst.failed))
