"""What a round of search estimated, as one value: printed in a few lines and kept in ``search.json``.

Schema (``{"format": SEARCH_FORMAT, ...}``, the file :data:`~coverage_engine.proposals.SEARCH_FILE` beside a
round's variants)::

    {"format": "scenario-coverage/search", "round": 2, "strategy": "boundary", "from": [...], "runs_read": 40,
     "objective": null, "maximise": false,
     "estimate": {"boundary": null | {"axes": {KEY: {"value": 53.2, "error": 0.4, "unit": "kph"}},
                                      "variants": [ASSIGNMENT, ...]},
                  "worst": null | {"objective": NAME, "value": -0.3, "assignment": ASSIGNMENT, "failed": true},
                  "holes": null | {"targeted": 5, "guessed": 2},
                  "done": false}}

``axes`` is filled where the boundary is one-dimensional (one axis varies); ``variants`` lists the runs
on either side of it, closer than the resolution; ``boundary`` also says how many neighbouring pairs of
runs disagree (``pairs``) and how many of them are located (``located``). ``done`` says the goal is met: the boundary
located to the resolution, a failing variant found, no hole left.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from coverage_engine.proposals import SEARCH_FORMAT
from coverage_engine.results.atomic import write_text_atomically

#: Most boundary variants kept in the estimate (the file stays small; the runs are in the results).
MAX_BOUNDARY_VARIANTS = 200


@dataclass(frozen=True)
class AxisBoundary:
    """Where pass turns to fail along one axis: the value and how far off it may be (half the gap left)."""

    value: float
    error: float
    unit: str = ""


@dataclass(frozen=True)
class BoundaryEstimate:
    """The boundary per axis (where it is one-dimensional), the runs beside it, and how many neighbouring
    pairs of runs disagree (``pairs``), of which ``located`` are within the resolution."""

    axes: Mapping[str, AxisBoundary] = field(default_factory=dict)
    variants: tuple[Mapping[str, object], ...] = ()
    pairs: int = 0
    located: int = 0


@dataclass(frozen=True)
class WorstCase:
    """The run with the worst objective value so far (lowest, or highest with ``--maximise``)."""

    objective: str
    value: float
    assignment: Mapping[str, object]
    failed: bool


@dataclass(frozen=True)
class HoleCount:
    """Holes aimed at: of the varied parameters and their crosses (``targeted``), of measured items (``guessed``)."""

    targeted: int
    guessed: int


@dataclass(frozen=True)
class Estimate:
    boundary: BoundaryEstimate | None = None
    worst: WorstCase | None = None
    holes: HoleCount | None = None
    done: bool = False


@dataclass(frozen=True)
class RoundRecord:
    """One round's ``search.json``: how it was proposed, from what, and the estimate."""

    round: int
    strategy: str
    sources: tuple[str, ...]
    runs_read: int
    estimate: Estimate
    objective: str | None = None
    maximise: bool = False


def _number(value: float) -> float | None:
    return value if math.isfinite(value) else None


def estimate_dict(estimate: Estimate) -> dict[str, Any]:
    boundary = estimate.boundary
    worst = estimate.worst
    holes = estimate.holes
    return {
        "boundary": None if boundary is None else {
            "axes": {key: {"value": _number(axis.value), "error": _number(axis.error), "unit": axis.unit}
                     for key, axis in boundary.axes.items()},
            "variants": [dict(v) for v in boundary.variants[:MAX_BOUNDARY_VARIANTS]],
            "pairs": boundary.pairs, "located": boundary.located},
        "worst": None if worst is None else {"objective": worst.objective, "value": _number(worst.value),
                                             "assignment": dict(worst.assignment), "failed": worst.failed},
        "holes": None if holes is None else {"targeted": holes.targeted, "guessed": holes.guessed},
        "done": estimate.done,
    }


def round_dict(record: RoundRecord) -> dict[str, Any]:
    """The JSON document of a round (what :func:`write_round` writes)."""
    return {"format": SEARCH_FORMAT, "round": record.round, "strategy": record.strategy,
            "from": list(record.sources), "runs_read": record.runs_read, "objective": record.objective,
            "maximise": record.maximise, "estimate": estimate_dict(record.estimate)}


def write_round(folder: str | Path, name: str, record: RoundRecord) -> Path:
    """Write the round's document as ``folder/name``, atomically."""
    text = json.dumps(round_dict(record), indent=1, ensure_ascii=False, allow_nan=False) + "\n"
    return write_text_atomically(Path(folder) / name, text)


def _shown(value: object) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _assignment_text(assignment: Mapping[str, object]) -> str:
    return ", ".join(f"{key} = {_shown(value)}" for key, value in assignment.items())


def estimate_lines(record: RoundRecord) -> list[str]:
    """The estimate in a few lines, as the command prints it."""
    estimate = record.estimate
    lines = [f"round {record.round}, strategy {record.strategy}: {record.runs_read} earlier run(s) read"]
    if estimate.boundary is not None:
        boundary = estimate.boundary
        for key, axis in boundary.axes.items():
            unit = axis.unit
            lines.append(f"boundary: {key} = {axis.value:.4g}{unit} ± {axis.error:.2g}{unit}")
        if not boundary.pairs:
            lines.append("boundary: not seen yet (no run failed, or none passed)")
        elif not boundary.axes:
            lines.append(f"boundary: {boundary.pairs} pair(s) of neighbouring runs disagree, {boundary.located} of "
                         f"them within the resolution ({len(boundary.variants)} run(s) beside the boundary)")
    if estimate.worst is not None:
        worst = estimate.worst
        lines.append(f"worst {worst.objective} = {worst.value:.4g} ({'failed' if worst.failed else 'passed'}) at "
                     f"{_assignment_text(worst.assignment)}")
    if estimate.holes is not None:
        holes = estimate.holes
        lines.append(f"holes: aiming at {holes.targeted} hole(s) of the varied parameters and their crosses"
                     + (f"; {holes.guessed} of measured items guessed at (inputs near the runs that came "
                        "closest: a guess)" if holes.guessed else ""))
    lines.append("goal met" if estimate.done else "goal not met yet")
    return lines
