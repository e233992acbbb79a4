"""One round of an adaptive strategy: from the variation's axes and the runs read, the points to try next
and the round's estimate (what ``scenario_variation --from`` prints and keeps in ``search.json``).

The variation pipeline turns the points into variants (``design_points``, under the same keeps and checks
as every sampler); this module only decides where they go.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from coverage_engine.coverage.run_records import ItemDecl
from coverage_engine.domains import numeric_value
from coverage_engine.proposals import FIRST_ROUND
from coverage_engine.search import ADAPTIVE
from coverage_engine.search.boundary import Observation, propose_boundary
from coverage_engine.search.errors import SearchError
from coverage_engine.search.estimate import (
    AxisBoundary,
    BoundaryEstimate,
    Estimate,
    LevelRate,
    PassRateEstimate,
    RoundRecord,
)
from coverage_engine.search.falsify import MARGIN, Scored, propose_falsify
from coverage_engine.search.history import History, PastRun
from coverage_engine.search.holes import propose_holes
from coverage_engine.search.pass_rate import RateRun, propose_pass_rate
from coverage_engine.search.space import Point, Space
from coverage_engine.search.target import SearchTarget

#: What a strategy's round gives: its points, its estimate and notes to print.
StrategyRound = tuple[tuple[Point, ...], Estimate, tuple[str, ...]]


@dataclass(frozen=True)
class SearchOptions:
    """The options of one adaptive round (the command line's, with the seed always set)."""

    strategy: str
    samples: int
    seed: int
    sources: tuple[str, ...]
    target: SearchTarget = SearchTarget()
    round_number: int | None = None


@dataclass(frozen=True)
class RoundProposal:
    """The points to try (unit cube, one coordinate per axis), the round's record, and notes to print."""

    points: tuple[Point, ...]
    record: RoundRecord
    notes: tuple[str, ...] = ()


def _placed(space: Space, history: History) -> list[tuple[PastRun, Point]]:
    placed = []
    for run in history.finished:
        point = space.point_of(run.assignment)
        if point is not None:
            placed.append((run, point))
    return placed


def _value(run: PastRun, objective: str, maximise: bool) -> float | None:
    values = run.records.get(objective, ())
    if not values:
        return None
    return max(values) if maximise else min(values)


def _failing(run: PastRun, options: SearchOptions) -> bool | None:
    """Which side of the boundary a run is on: failed, or its objective below the threshold (None: unknown)."""
    if options.target.threshold is None:
        return run.failed
    assert options.target.objective is not None
    value = _value(run, options.target.objective, False)
    return None if value is None else value < options.target.threshold


def _boundary(space: Space, placed: Sequence[tuple[PastRun, Point]], options: SearchOptions) -> StrategyRound:
    if options.target.pass_rate is not None:
        return _rate_boundary(space, placed, options)
    observations = []
    for run, point in placed:
        failing = _failing(run, options)
        if failing is not None:
            observations.append(Observation(point, failing, run.assignment))
    proposal = propose_boundary(space, observations, options.samples, options.target.resolution, options.seed)
    return proposal.points, Estimate(boundary=proposal.estimate, done=proposal.done), ()


def along_axis(space: Space, along: str | None) -> int:
    """The axis ``--along`` names: its key, or a dotted part of exactly one key (``noise`` for
    ``nav.noise.parameter_value``)."""
    if along is None:
        raise SearchError("--pass-rate needs --along KEY: the varied parameter whose level the rate crosses at "
                          f"(one of {', '.join(space.keys)})")
    if along in space.keys:
        return space.keys.index(along)
    found = [i for i, key in enumerate(space.keys) if along in key.split(".")]
    if len(found) != 1:
        which = "names more than one" if found else "names none"
        raise SearchError(f"--along {along} {which} of the varied parameters ({', '.join(space.keys)})")
    return found[0]


def _rate_boundary(space: Space, placed: Sequence[tuple[PastRun, Point]], options: SearchOptions) -> StrategyRound:
    """``--pass-rate R --along KEY``: the level of KEY where the share of passing runs crosses R."""
    assert options.target.pass_rate is not None
    along = along_axis(space, options.target.along)
    runs = []
    for run, point in placed:
        failing = _failing(run, options)
        if failing is not None:
            runs.append(RateRun(point, not failing))
    proposal = propose_pass_rate(space, runs, along, options.target.pass_rate, options.samples, options.target.resolution,
                                 options.seed)
    found = proposal.boundary
    key = space.keys[along]
    levels = tuple(LevelRate(space.value_at(along, level.coordinate), level.runs, level.passed, level.decided)
                   for level in found.levels)
    axes = {}
    if found.before is not None and found.after is not None:
        low = numeric_value(space.value_at(along, found.before.coordinate))
        high = numeric_value(space.value_at(along, found.after.coordinate))
        if low is not None and high is not None:
            axes[key] = AxisBoundary((low + high) / 2, abs(high - low) / 2, space.axes[along].unit)
    estimate = BoundaryEstimate(axes, located=int(found.located),
                                pass_rate=PassRateEstimate(options.target.pass_rate, key, levels))
    return proposal.points, Estimate(boundary=estimate, done=found.located), ()


def _falsify(space: Space, placed: Sequence[tuple[PastRun, Point]], options: SearchOptions) -> StrategyRound:
    objective = options.target.objective or MARGIN
    scored = []
    for run, point in placed:
        value = _value(run, objective, options.target.maximise)
        if value is not None:
            scored.append(Scored(point, value, run.failed, run.assignment))
    notes: tuple[str, ...] = ()
    if placed and not scored:
        notes = (f"no run read recorded '{objective}': the optimiser starts from scratch",)
    proposal = propose_falsify(space, scored, options.samples, options.seed, objective, options.target.maximise,
                               any(run.failed for run, _ in placed))
    return proposal.points, Estimate(worst=proposal.worst, done=proposal.done), notes


def _measured(history: History, space: Space, placed: Sequence[tuple[PastRun, Point]]) \
        -> list[tuple[ItemDecl, list[tuple[Point, Sequence[object]]]]]:
    found: list[tuple[ItemDecl, list[tuple[Point, Sequence[object]]]]] = []
    for decl in history.covers.values():
        values: list[tuple[Point, Sequence[object]]] = [(point, run.covers.get(decl.name, ())) for run, point in placed]
        found.append((decl, values))
    return found


def _holes(space: Space, history: History, placed: Sequence[tuple[PastRun, Point]],
           options: SearchOptions) -> StrategyRound:
    proposal = propose_holes(space, [p for _, p in placed], [r.assignment for r, _ in placed], options.samples,
                             options.seed, history.domains, _measured(history, space, placed))
    notes = tuple(f"a guess: aiming at {name} near the run whose value came closest (what a run measures "
                  "cannot be chosen)" for name in proposal.guessed)
    return proposal.points, Estimate(holes=proposal.holes, done=proposal.done), notes


def propose_round(space: Space, history: History, options: SearchOptions) -> RoundProposal:
    """The points of one round of ``options.strategy`` over ``space``, from ``history``."""
    if options.strategy not in ADAPTIVE:
        raise SearchError(f"'{options.strategy}' is not an adaptive strategy (one of {', '.join(ADAPTIVE)})")
    if options.target.threshold is not None and options.target.objective is None:
        raise SearchError("--threshold needs --objective NAME: the record() item whose values cross it")
    if options.target.along is not None and options.target.pass_rate is None:
        raise SearchError("--along goes with --pass-rate R: the rate whose crossing along it is sought")
    if options.target.pass_rate is not None and options.strategy != "boundary":
        raise SearchError(f"--pass-rate is an option of --strategy boundary, not of {options.strategy}")
    placed = _placed(space, history)
    if options.strategy == "boundary":
        points, estimate, notes = _boundary(space, placed, options)
    elif options.strategy == "falsify":
        points, estimate, notes = _falsify(space, placed, options)
    else:
        points, estimate, notes = _holes(space, history, placed, options)
    number = options.round_number or max(history.last_round, FIRST_ROUND - 1) + 1
    record = RoundRecord(number, options.strategy, options.sources, len(history.runs), estimate,
                         options.target.objective if options.strategy != "falsify" else options.target.objective or MARGIN,
                         options.target.maximise)
    left_out = len(history.finished) - len(placed)
    extra = (f"{left_out} run(s) whose values lie outside the variation's axes were left out",) if left_out else ()
    return RoundProposal(points, record, history.notes + extra + notes)


def estimate_round(space: Space, history: History, options: SearchOptions) -> RoundRecord:
    """What ``options.strategy`` estimates from ``history`` without proposing a variant (the search's last
    word once its last round ran: every run counted). The round is the last one read unless
    ``options.round_number`` says. ``fill-holes`` counts the holes a round of ``options.samples`` would aim
    at (the holes left); the boundary and the worst case do not depend on the samples, so none is asked for."""
    samples = options.samples if options.strategy == "fill-holes" else 0
    number = options.round_number or max(history.last_round, FIRST_ROUND)
    return propose_round(space, history, replace(options, samples=samples, round_number=number)).record
