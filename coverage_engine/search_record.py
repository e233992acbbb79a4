"""The one model of ``search.json``: its values, its writer, its reader, and its text.

``scenario_search`` works in one folder, one subfolder per round (:func:`round_folder`), each holding
the round's variants and its results::

    search/search.json                 the search: its settings, its rounds, the latest estimate
    search/round1/variants/*.sce        what round 1 ran (and its own search.json, when it estimated)
    search/round1/results/              the batch of round 1 (test.xml, a folder per job, search.json)

The ``search.json`` of a round is written by ``scenario_variation --from`` (issue 35); the search's own
file has the same fields for its latest estimate, plus ``rounds`` (the runs and failures of each) and
``settings`` (what ``--resume`` continues with)::

    {"format": "scenario-coverage/search", "round": 2, "strategy": "boundary", "from": [...], "runs_read": 40,
     "objective": null, "maximise": false,
     "estimate": {"boundary": null | {"axes": {KEY: {"value": 53.2, "error": 0.4, "unit": "kph"}},
                                      "variants": [ASSIGNMENT, ...], "pairs": 5, "located": 2},
                  "worst": null | {"objective": NAME, "value": -0.3, "assignment": ASSIGNMENT, "failed": true},
                  "holes": null | {"targeted": 5, "guessed": 2},
                  "done": false},
     "rounds": [{"round": 1, "strategy": "lhs", "runs": 40, "failed": 3}, ...], "settings": {...}}

``axes`` is filled where the boundary is one-dimensional; ``variants`` lists the runs on either side of
it; ``pairs`` counts the neighbouring runs that disagree and ``located`` those within the resolution. With
``boundary --pass-rate`` the boundary also holds ``"pass_rate": {"rate": 0.5, "along": KEY, "levels": [{"value":
V, "runs": 8, "passed": 3, "side": "below"}, ...]}`` (``side``: ``above`` means at or above the rate, null while
undecided), and ``axes`` the crossing along KEY once a level on each side is decided.
``done`` says the goal is met. The adaptive strategies build these values (:mod:`coverage_engine.search`
sits above this module), the search loop and the coverage report read them back, and all of them say an
estimate with :func:`estimate_lines`, so it reads the same everywhere. A file that is not there, not JSON
or not of :data:`SEARCH_FORMAT` reads as None.
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

from coverage_engine.limits import read_bounded
from coverage_engine.proposals import FIRST_ROUND, SEARCH_FILE, SEARCH_FORMAT
from coverage_engine.results.atomic import write_text_atomically

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


#: A run's assignment as stored (parameter key -> value), in the order the run lists them.
Assignment = Mapping[str, object]

#: The sides of ``--pass-rate`` a level is decided on: at or above the rate, or below it.
ABOVE, BELOW = "above", "below"

#: Most boundary variants kept in an estimate (the file stays small; the runs are in the results).
MAX_BOUNDARY_VARIANTS = 200


@dataclass(frozen=True)
class AxisBoundary:
    """Where pass turns to fail along one parameter: the value, how far off it may be (half the gap left;
    None when the file does not say), its unit."""

    value: float
    error: float | None
    unit: str = ""


@dataclass(frozen=True)
class LevelRate:
    """``--pass-rate``: one level run along the parameter, its runs and passes, and the side of the rate it is
    decided on (``above`` means at or above; None while its other cells could still tip it)."""

    value: object
    runs: int
    passed: int
    side: str | None


@dataclass(frozen=True)
class PassRateEstimate:
    """``boundary --pass-rate R --along KEY``: the rate, the parameter, and what each level run so far gave."""

    rate: float
    along: str
    levels: tuple[LevelRate, ...] = ()


@dataclass(frozen=True)
class BoundaryEstimate:
    """The boundary located so far: per axis (key -> :class:`AxisBoundary`) where it is one-dimensional,
    the runs beside it, how many neighbouring pairs of runs disagree (``pairs``) and how many of those are
    within the resolution (``located``)."""

    axes: Mapping[str, AxisBoundary] = field(default_factory=dict)
    variants: tuple[Assignment, ...] = ()
    pairs: int = 0
    located: int = 0
    #: With ``--pass-rate``: the levels run along the parameter and their pass rates.
    pass_rate: PassRateEstimate | None = None


@dataclass(frozen=True)
class WorstCase:
    """The run with the worst objective value so far (lowest, or highest with ``--maximise``)."""

    objective: str
    value: float
    assignment: Assignment
    failed: bool


@dataclass(frozen=True)
class HoleCount:
    """Holes aimed at: of the varied parameters and their crosses (``targeted``), of measured items (``guessed``)."""

    targeted: int
    guessed: int


@dataclass(frozen=True)
class Estimate:
    """What a round estimated; ``done`` when the goal is met (the boundary located to the resolution, a
    failing variant found, no hole left)."""

    boundary: BoundaryEstimate | None = None
    worst: WorstCase | None = None
    holes: HoleCount | None = None
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
    """A ``search.json``: a round's (written by ``scenario_variation --from``: how it was proposed, from
    what, and the estimate), or a search's own (the latest round's fields, plus its ``rounds`` and the
    ``settings`` that ``--resume`` continues with)."""

    round: int
    strategy: str
    sources: tuple[str, ...] = ()
    runs_read: int = 0
    estimate: Estimate = field(default_factory=Estimate)
    objective: str | None = None
    maximise: bool = False
    rounds: tuple[RoundSummary, ...] = ()
    settings: Mapping[str, Any] = field(default_factory=dict)


def _number(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if math.isfinite(value) else None


def _count(value: object) -> int:
    return value if isinstance(value, int) and not isinstance(value, bool) and value >= 0 else 0


def _assignment(value: object) -> Assignment:
    if not isinstance(value, dict):
        return {}
    return {str(k): v for k, v in value.items() if isinstance(v, (str, int, float, bool))}


def _boundary(value: object) -> BoundaryEstimate | None:
    if not isinstance(value, dict):
        return None
    axes = {}
    for key, axis in (value.get("axes") or {}).items() if isinstance(value.get("axes"), dict) else ():
        where = _number(axis.get("value")) if isinstance(axis, dict) else None
        if where is not None:
            unit = axis.get("unit")
            axes[str(key)] = AxisBoundary(where, _number(axis.get("error")), unit if isinstance(unit, str) else "")
    variants = value.get("variants")
    listed = tuple(_assignment(v) for v in variants) if isinstance(variants, list) else ()
    return BoundaryEstimate(axes, tuple(v for v in listed if v), _count(value.get("pairs")),
                            _count(value.get("located")), _pass_rate(value.get("pass_rate")))


def _pass_rate(value: object) -> PassRateEstimate | None:
    if not isinstance(value, dict):
        return None
    rate = _number(value.get("rate"))
    along = value.get("along")
    if rate is None or not isinstance(along, str):
        return None
    levels = []
    for level in value.get("levels") or () if isinstance(value.get("levels"), list) else ():
        if isinstance(level, dict) and isinstance(level.get("value"), (str, int, float)):
            side = level.get("side")
            levels.append(LevelRate(level["value"], _count(level.get("runs")), _count(level.get("passed")),
                                    side if side in (ABOVE, BELOW) else None))
    return PassRateEstimate(rate, along, tuple(levels))


def _worst(value: object) -> WorstCase | None:
    if not isinstance(value, dict):
        return None
    number = _number(value.get("value"))
    if number is None:
        return None
    return WorstCase(str(value.get("objective") or ""), number, _assignment(value.get("assignment")),
                     value.get("failed") is True)


def _holes(value: object) -> HoleCount | None:
    if not isinstance(value, dict):
        return None
    targeted, guessed = value.get("targeted"), value.get("guessed")
    if not isinstance(targeted, int) or not isinstance(guessed, int):
        return None
    return HoleCount(targeted, guessed)


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
        estimate=Estimate(_boundary(estimate.get("boundary")), _worst(estimate.get("worst")),
                          _holes(estimate.get("holes")), estimate.get("done") is True),
        objective=objective if isinstance(objective, str) else None,
        maximise=document.get("maximise") is True,
        rounds=_rounds(document.get("rounds")), settings=settings if isinstance(settings, dict) else {})


def read_search_record(folder: str | os.PathLike[str]) -> SearchRecord | None:
    """The ``search.json`` of ``folder`` (a search's folder, a round's variants or results), else None."""
    data = read_bounded(Path(folder) / SEARCH_FILE, MAX_SEARCH_BYTES)
    if data is None:
        return None
    try:
        document = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        return None
    return parse_search_record(document)


def _finite(value: float | None) -> float | None:
    """JSON has no infinity or NaN: those are written as null (and read back as "not known")."""
    return value if value is not None and math.isfinite(value) else None


def _rate_dict(rates: PassRateEstimate) -> dict[str, Any]:
    return {"rate": rates.rate, "along": rates.along,
            "levels": [{"value": level.value, "runs": level.runs, "passed": level.passed, "side": level.side}
                       for level in rates.levels]}


def estimate_dict(estimate: Estimate) -> dict[str, Any]:
    """The ``estimate`` of a ``search.json`` (the form :func:`parse_search_record` reads)."""
    boundary = estimate.boundary
    worst = estimate.worst
    holes = estimate.holes
    return {
        "boundary": None if boundary is None else {
            "axes": {key: {"value": _finite(axis.value), "error": _finite(axis.error), "unit": axis.unit}
                     for key, axis in boundary.axes.items()},
            "variants": [dict(v) for v in boundary.variants[:MAX_BOUNDARY_VARIANTS]],
            "pairs": boundary.pairs, "located": boundary.located,
            **({} if boundary.pass_rate is None else {"pass_rate": _rate_dict(boundary.pass_rate)})},
        "worst": None if worst is None else {"objective": worst.objective, "value": _finite(worst.value),
                                             "assignment": dict(worst.assignment), "failed": worst.failed},
        "holes": None if holes is None else {"targeted": holes.targeted, "guessed": holes.guessed},
        "done": estimate.done,
    }


def search_document(record: SearchRecord) -> dict[str, Any]:
    """The whole ``search.json`` of ``record``: a round's, or (with settings) a search's own, which adds the
    rounds run and the settings."""
    document: dict[str, Any] = {
        "format": SEARCH_FORMAT, "round": record.round, "strategy": record.strategy, "from": list(record.sources),
        "runs_read": record.runs_read, "objective": record.objective, "maximise": record.maximise,
        "estimate": estimate_dict(record.estimate)}
    if record.settings or record.rounds:
        document["rounds"] = [{"round": r.round, "strategy": r.strategy, "runs": r.runs, "failed": r.failed}
                              for r in record.rounds]
    if record.settings:
        document["settings"] = dict(record.settings)
    return document


def write_search_record(folder: str | os.PathLike[str], record: SearchRecord, name: str = SEARCH_FILE) -> Path:
    """Write ``record`` as ``folder/name`` (``search.json``), atomically: a reader never sees half a file."""
    text = json.dumps(search_document(record), indent=1, ensure_ascii=False, allow_nan=False) + "\n"
    return write_text_atomically(Path(folder) / name, text)


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
    return ", ".join(f"{short_key(k)}={value_text(v)}" for k, v in assignment.items())


def axis_text(key: str, axis: AxisBoundary) -> str:
    """``speed = 53.2 ± 0.4 kph``."""
    unit = f" {axis.unit}" if axis.unit else ""
    error = f" ± {axis.error:.2g}" if axis.error is not None else ""
    return f"{short_key(key)} = {axis.value:.4g}{error}{unit}"


#: What the estimate says of a boundary not seen yet.
NOT_SEEN = "boundary: not seen yet (no run failed, or none passed)"


def _pairs_text(boundary: BoundaryEstimate) -> str:
    """``boundary: 3 pair(s) of neighbouring runs disagree, 1 of them located to the resolution``."""
    return (f"boundary: {boundary.pairs} pair(s) of neighbouring runs disagree, {boundary.located} of them "
            "located to the resolution")


def _holes_text(holes: HoleCount) -> str:
    guessed = (f"; {holes.guessed} of measured items guessed at (inputs near the runs that came closest: a guess)"
               if holes.guessed else "")
    return f"holes: aiming at {holes.targeted} hole(s) of the varied parameters and their crosses{guessed}"


def estimate_summary(estimate: Estimate) -> str:
    """The estimate on one line (for a progress line): the boundary, the worst case or the holes."""
    parts = []
    boundary = estimate.boundary
    if boundary is not None and boundary.axes:
        parts.append("boundary " + "; ".join(axis_text(k, a) for k, a in boundary.axes.items()))
    elif boundary is not None and boundary.pass_rate is not None:
        parts.append(f"pass rate of {rate_text(boundary.pass_rate.rate)} not crossed between decided levels yet")
    elif boundary is not None and boundary.pairs:
        parts.append(f"boundary: {boundary.pairs} pair(s) of neighbouring runs disagree, {boundary.located} "
                     "located")
    elif boundary is not None and boundary.variants:
        parts.append(f"boundary: {len(boundary.variants)} variant(s) where pass turns to fail")
    elif boundary is not None:
        parts.append("boundary not seen yet")
    if estimate.worst is not None:
        worst = estimate.worst
        parts.append(f"worst {worst.objective or 'value'} {worst.value:.4g}" + (" (failed)" if worst.failed else ""))
    if estimate.holes is not None:
        parts.append(f"{estimate.holes.targeted} hole(s) aimed at")
    if estimate.done:
        parts.append("goal met")
    return ", ".join(parts) or "no estimate yet"


def rate_text(rate: float) -> str:
    """``50 %``."""
    return f"{rate * 100:.4g} %"


def _rate_lines(rates: PassRateEstimate) -> list[str]:
    """The pass rate of each level run, and which side of the rate each is decided on."""
    shown = rate_text(rates.rate)
    sides = {ABOVE: f"at or above {shown}", BELOW: f"below {shown}", None: "not decided yet"}
    parts = [f"{value_text(level.value)}: {level.passed} of {level.runs} passed ({sides[level.side]})"
             for level in rates.levels]
    return [f"pass rate along {short_key(rates.along)}: " + ("; ".join(parts) if parts else "no run yet")]


def _boundary_lines(boundary: BoundaryEstimate) -> list[str]:
    lines = [f"boundary: {axis_text(key, axis)}" for key, axis in boundary.axes.items()]
    if boundary.pass_rate is not None:
        rates = boundary.pass_rate
        if not boundary.axes:
            lines.append(f"boundary: not seen yet (no level of {short_key(rates.along)} decided on each side of "
                         f"{rate_text(rates.rate)})")
        return lines + _rate_lines(rates)
    if boundary.axes:
        return lines
    if boundary.pairs:
        lines.append(_pairs_text(boundary))
    if boundary.variants:
        lines.append(f"boundary: {len(boundary.variants)} variant(s) where pass turns to fail")
        lines.extend(f"  {assignment_text(variant)}" for variant in boundary.variants[:LIST_VARIANTS_UP_TO])
        if len(boundary.variants) > LIST_VARIANTS_UP_TO:
            lines.append(f"  ... {len(boundary.variants) - LIST_VARIANTS_UP_TO} more")
    return lines or [NOT_SEEN]


def estimate_lines(estimate: Estimate) -> list[str]:
    """The estimate in a few lines: what ``scenario_variation --from`` prints under its round's heading,
    the search's last words, and the report's ``Search`` section (one rendering, so they read alike)."""
    lines = _boundary_lines(estimate.boundary) if estimate.boundary is not None else []
    worst = estimate.worst
    if worst is not None:
        verdict = "failed" if worst.failed else "passed"
        lines.append(f"worst case: {worst.objective or 'value'} = {worst.value:.4g} ({verdict}) at "
                     f"{assignment_text(worst.assignment)}")
    if estimate.holes is not None:
        lines.append(_holes_text(estimate.holes))
    lines.append("goal met" if estimate.done else "goal not met yet")
    return lines


def round_heading(record: SearchRecord) -> str:
    """``round 2, strategy boundary: 40 earlier run(s) read`` (the first line of a round's estimate)."""
    return f"round {record.round}, strategy {record.strategy}: {record.runs_read} earlier run(s) read"
