"""What a search leaves in its folder, read back: the rounds, and what the latest round estimated.

``scenario_search`` works in one folder, one subfolder per round (:func:`round_folder`), each holding
the round's variants and its results::

    search/search.json                 the search: its settings, its rounds, the latest estimate
    search/round1/variants/*.sce        what round 1 ran (and its own search.json, when it estimated)
    search/round1/results/              the batch of round 1 (test.xml, a folder per job, search.json)

The ``search.json`` of a round is written by ``scenario_variation --from`` (issue 35): the round, the
strategy, the results read and the estimate (the boundary located so far, the worst case found, the
holes aimed at, whether the goal is met). The search's own file has the same fields for its latest
round, plus ``rounds`` (the runs and failures of each) and ``settings`` (what ``--resume`` continues
with). This module reads either into a :class:`SearchRecord` and says it in a few lines of text; the
search loop, the coverage report and the progress lines all use it, so the estimate reads the same
everywhere. A file that is not there, not JSON or not of :data:`SEARCH_FORMAT` reads as None.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from coverage_engine.proposals import FIRST_ROUND, SEARCH_FILE, SEARCH_FORMAT

#: A round's folder is this prefix and the round's number (``round1``, ``round2``, …).
ROUND_PREFIX = "round"

#: The folder of a round's variants and the folder of its results, inside the round's folder.
VARIANTS_FOLDER = "variants"
RESULTS_FOLDER = "results"

#: Largest ``search.json`` read (the estimate's variants are a few hundred assignments at most).
MAX_SEARCH_BYTES = 16 * 1024 * 1024

#: Boundary variants listed in the text of an estimate (the rest are counted).
LIST_VARIANTS_UP_TO = 3

_ROUND_NAME = re.compile(rf"{ROUND_PREFIX}([1-9][0-9]{{0,5}})")


def round_folder(number: int) -> str:
    """The name of round ``number``'s folder inside the search's folder."""
    return f"{ROUND_PREFIX}{number}"


def round_folders(folder: str | os.PathLike[str]) -> list[tuple[int, Path]]:
    """The round folders of a search's folder that hold a results folder, in round order."""
    found = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return []
    for entry in entries:
        match = _ROUND_NAME.fullmatch(entry.name)
        results = Path(entry.path) / RESULTS_FOLDER
        if match and entry.is_dir(follow_symlinks=False) and results.is_dir() and not results.is_symlink():
            found.append((int(match.group(1)), results))
    return sorted(found)


Assignment = tuple[tuple[str, object], ...]


@dataclass(frozen=True)
class BoundaryAxis:
    """Where pass turns to fail along one parameter: the value, how far off it may be, its unit."""

    key: str
    value: float
    error: float | None
    unit: str


@dataclass(frozen=True)
class Boundary:
    """The boundary located so far: per axis where it is one-dimensional, else the variants on it."""

    axes: tuple[BoundaryAxis, ...] = ()
    variants: tuple[Assignment, ...] = ()
    #: Neighbouring pairs of runs that disagree, and how many of them are located to the resolution
    #: (None when the file does not say).
    pairs: int | None = None
    located: int | None = None


@dataclass(frozen=True)
class WorstCase:
    """The worst variant found by ``falsify``: its objective's value and its assignment."""

    objective: str
    value: float
    assignment: Assignment
    failed: bool


@dataclass(frozen=True)
class HoleTargets:
    """How many holes ``fill-holes`` aimed at, and how many of them by a guess (holes of measured values)."""

    targeted: int
    guessed: int


@dataclass(frozen=True)
class Estimate:
    """What a round estimated; ``done`` when the goal is met."""

    boundary: Boundary | None = None
    worst: WorstCase | None = None
    holes: HoleTargets | None = None
    done: bool = False

    @property
    def empty(self) -> bool:
        return self.boundary is None and self.worst is None and self.holes is None


@dataclass(frozen=True)
class RoundSummary:
    """One round of a search: its number, the strategy that chose its variants, its runs and failures."""

    round: int
    strategy: str
    runs: int
    failed: int


@dataclass(frozen=True)
class SearchRecord:
    """A ``search.json``: the round (the latest, for the search's own file), its strategy and estimate."""

    round: int
    strategy: str
    sources: tuple[str, ...] = ()
    runs_read: int = 0
    objective: str | None = None
    maximise: bool = False
    estimate: Estimate = field(default_factory=Estimate)
    rounds: tuple[RoundSummary, ...] = ()
    settings: Mapping[str, Any] = field(default_factory=dict)


def _number(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if math.isfinite(value) else None


def _assignment(value: object) -> Assignment:
    if not isinstance(value, dict):
        return ()
    return tuple((str(k), v) for k, v in value.items() if isinstance(v, (str, int, float, bool)))


def _boundary(value: object) -> Boundary | None:
    if not isinstance(value, dict):
        return None
    axes = []
    for key, axis in (value.get("axes") or {}).items() if isinstance(value.get("axes"), dict) else ():
        where = _number(axis.get("value")) if isinstance(axis, dict) else None
        if where is not None:
            unit = axis.get("unit")
            axes.append(BoundaryAxis(str(key), where, _number(axis.get("error")), unit if isinstance(unit, str) else ""))
    variants = value.get("variants")
    listed = tuple(_assignment(v) for v in variants) if isinstance(variants, list) else ()
    pairs, located = value.get("pairs"), value.get("located")
    return Boundary(tuple(axes), tuple(v for v in listed if v),
                    pairs if isinstance(pairs, int) and not isinstance(pairs, bool) else None,
                    located if isinstance(located, int) and not isinstance(located, bool) else None)


def _worst(value: object) -> WorstCase | None:
    if not isinstance(value, dict):
        return None
    number = _number(value.get("value"))
    if number is None:
        return None
    return WorstCase(str(value.get("objective") or ""), number, _assignment(value.get("assignment")),
                     value.get("failed") is True)


def _holes(value: object) -> HoleTargets | None:
    if not isinstance(value, dict):
        return None
    targeted, guessed = value.get("targeted"), value.get("guessed")
    if not isinstance(targeted, int) or not isinstance(guessed, int):
        return None
    return HoleTargets(targeted, guessed)


def _rounds(value: object) -> tuple[RoundSummary, ...]:
    if not isinstance(value, list):
        return ()
    rounds = []
    for entry in value:
        if isinstance(entry, dict) and all(isinstance(entry.get(k), int) for k in ("round", "runs", "failed")):
            rounds.append(RoundSummary(entry["round"], str(entry.get("strategy") or ""), entry["runs"],
                                       entry["failed"]))
    return tuple(rounds)


def parse_search_record(document: object) -> SearchRecord | None:
    """The record of a parsed ``search.json`` document (None when it is not one)."""
    if not isinstance(document, dict) or document.get("format") != SEARCH_FORMAT:
        return None
    number = document.get("round")
    found = document.get("estimate")
    estimate: dict[str, Any] = found if isinstance(found, dict) else {}
    sources = document.get("from")
    objective = document.get("objective")
    settings = document.get("settings")
    return SearchRecord(
        round=number if isinstance(number, int) and not isinstance(number, bool) else FIRST_ROUND,
        strategy=str(document.get("strategy") or ""),
        sources=tuple(str(s) for s in sources) if isinstance(sources, list) else (),
        runs_read=document["runs_read"] if isinstance(document.get("runs_read"), int) else 0,
        objective=objective if isinstance(objective, str) else None,
        maximise=document.get("maximise") is True,
        estimate=Estimate(_boundary(estimate.get("boundary")), _worst(estimate.get("worst")),
                          _holes(estimate.get("holes")), estimate.get("done") is True),
        rounds=_rounds(document.get("rounds")), settings=settings if isinstance(settings, dict) else {})


def read_search_record(folder: str | os.PathLike[str]) -> SearchRecord | None:
    """The ``search.json`` of ``folder`` (a search's folder, a round's variants or results), else None."""
    path = Path(folder) / SEARCH_FILE
    try:
        if path.is_symlink() or not path.is_file() or path.stat().st_size > MAX_SEARCH_BYTES:
            return None
        document = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):
        return None
    return parse_search_record(document)


def _assignment_dict(assignment: Assignment) -> dict[str, object]:
    return dict(assignment)


def estimate_document(estimate: Estimate) -> dict[str, Any]:
    """The ``estimate`` of a ``search.json`` (the form :func:`parse_search_record` reads)."""
    boundary = estimate.boundary
    worst = estimate.worst
    return {
        "boundary": None if boundary is None else {
            "axes": {a.key: {"value": a.value, "error": a.error, "unit": a.unit} for a in boundary.axes},
            "variants": [_assignment_dict(v) for v in boundary.variants],
            **({"pairs": boundary.pairs} if boundary.pairs is not None else {}),
            **({"located": boundary.located} if boundary.located is not None else {})},
        "worst": None if worst is None else {"objective": worst.objective, "value": worst.value,
                                             "assignment": _assignment_dict(worst.assignment),
                                             "failed": worst.failed},
        "holes": None if estimate.holes is None else {"targeted": estimate.holes.targeted,
                                                      "guessed": estimate.holes.guessed},
        "done": estimate.done}


def search_document(record: SearchRecord) -> dict[str, Any]:
    """The whole ``search.json`` of ``record`` (a search's own file: with its rounds and settings)."""
    document: dict[str, Any] = {
        "format": SEARCH_FORMAT, "round": record.round, "strategy": record.strategy, "from": list(record.sources),
        "runs_read": record.runs_read, "objective": record.objective, "maximise": record.maximise,
        "estimate": estimate_document(record.estimate),
        "rounds": [{"round": r.round, "strategy": r.strategy, "runs": r.runs, "failed": r.failed}
                   for r in record.rounds]}
    if record.settings:
        document["settings"] = dict(record.settings)
    return document


def short_key(key: str) -> str:
    """A parameter's key without its scenario (``brake.speed`` → ``speed``), as reports name it."""
    return key.split(".", 1)[-1]


def value_text(value: object) -> str:
    """A value of an assignment as the estimate shows it: numbers to 4 significant digits."""
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def assignment_text(assignment: Assignment) -> str:
    """``speed=84.27, gap=30`` (keys without their scenario)."""
    return ", ".join(f"{short_key(k)}={value_text(v)}" for k, v in assignment)


def axis_text(axis: BoundaryAxis) -> str:
    """``speed = 53.2 ± 0.4 kph``."""
    unit = f" {axis.unit}" if axis.unit else ""
    error = f" ± {axis.error:.2g}" if axis.error is not None else ""
    return f"{short_key(axis.key)} = {axis.value:.4g}{error}{unit}"


def _pairs_text(boundary: Boundary) -> str:
    """``boundary: 3 pair(s) of neighbouring runs disagree, 1 located``, or that none disagree yet."""
    if not boundary.pairs:
        return "boundary: not seen yet (no neighbouring runs disagree)"
    return f"boundary: {boundary.pairs} pair(s) of neighbouring runs disagree, {boundary.located or 0} located"


def estimate_summary(estimate: Estimate) -> str:
    """The estimate on one line (for a progress line): the boundary, the worst case or the holes."""
    parts = []
    boundary = estimate.boundary
    if boundary is not None and boundary.axes:
        parts.append("boundary " + "; ".join(axis_text(a) for a in boundary.axes))
    elif boundary is not None and boundary.variants:
        parts.append(f"boundary: {len(boundary.variants)} variant(s) where pass turns to fail")
    elif boundary is not None and boundary.pairs is not None:
        parts.append(_pairs_text(boundary))
    if estimate.worst is not None:
        worst = estimate.worst
        parts.append(f"worst {worst.objective or 'value'} {worst.value:.4g}" + (" (failed)" if worst.failed else ""))
    if estimate.holes is not None:
        parts.append(f"{estimate.holes.targeted} hole(s) aimed at")
    if estimate.done:
        parts.append("goal met")
    return ", ".join(parts) or "no estimate yet"


def estimate_lines(estimate: Estimate) -> list[str]:
    """The estimate in a few lines (the search's last words, and the report's ``Search`` section)."""
    lines = []
    boundary = estimate.boundary
    if boundary is not None:
        if boundary.pairs is not None and not boundary.axes:
            lines.append(_pairs_text(boundary))
        for axis in boundary.axes:
            lines.append(f"boundary: {axis_text(axis)}")
        if boundary.variants and not boundary.axes:
            lines.append(f"boundary: {len(boundary.variants)} variant(s) where pass turns to fail")
            for variant in boundary.variants[:LIST_VARIANTS_UP_TO]:
                lines.append(f"  {assignment_text(variant)}")
            if len(boundary.variants) > LIST_VARIANTS_UP_TO:
                lines.append(f"  ... {len(boundary.variants) - LIST_VARIANTS_UP_TO} more")
    worst = estimate.worst
    if worst is not None:
        verdict = "failed" if worst.failed else "passed"
        lines.append(f"worst case: {worst.objective or 'value'} = {worst.value:.4g} ({verdict}) at "
                     f"{assignment_text(worst.assignment)}")
    holes = estimate.holes
    if holes is not None:
        guessed = f", {holes.guessed} of them by a guess (holes of measured values)" if holes.guessed else ""
        lines.append(f"holes: {holes.targeted} aimed at{guessed}")
    lines.append("goal met" if estimate.done else "goal not met yet")
    return lines
