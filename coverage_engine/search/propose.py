"""One round of an adaptive strategy: from the variation's axes and the runs read, the points to try next
and the round's estimate (what ``scenario_variation --from`` prints and keeps in ``search.json``).

The variation pipeline turns the points into variants (``design_points``, under the same keeps and checks
as every sampler); this module only decides where they go.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from coverage_engine.coverage.run_records import ItemDecl
from coverage_engine.proposals import FIRST_ROUND
from coverage_engine.search import ADAPTIVE, DEFAULT_RESOLUTION
from coverage_engine.search.boundary import Observation, propose_boundary
from coverage_engine.search.errors import SearchError
from coverage_engine.search.estimate import Estimate, RoundRecord
from coverage_engine.search.falsify import MARGIN, Scored, propose_falsify
from coverage_engine.search.history import History, PastRun
from coverage_engine.search.holes import propose_holes
from coverage_engine.search.space import Point, Space

#: What a strategy's round gives: its points, its estimate and notes to print.
StrategyRound = tuple[tuple[Point, ...], Estimate, tuple[str, ...]]


@dataclass(frozen=True)
class SearchOptions:
    """The options of one adaptive round (the command line's, with the seed always set)."""

    strategy: str
    samples: int
    seed: int
    sources: tuple[str, ...]
    objective: str | None = None
    maximise: bool = False
    threshold: float | None = None
    resolution: float = DEFAULT_RESOLUTION
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


def _boundary(space: Space, placed: Sequence[tuple[PastRun, Point]], options: SearchOptions) -> StrategyRound:
    observations = []
    for run, point in placed:
        if options.threshold is None:
            failing = run.failed
        else:
            assert options.objective is not None
            value = _value(run, options.objective, False)
            if value is None:
                continue
            failing = value < options.threshold
        observations.append(Observation(point, failing, run.assignment))
    proposal = propose_boundary(space, observations, options.samples, options.resolution, options.seed)
    return proposal.points, Estimate(boundary=proposal.estimate, done=proposal.done), ()


def _falsify(space: Space, placed: Sequence[tuple[PastRun, Point]], options: SearchOptions) -> StrategyRound:
    objective = options.objective or MARGIN
    scored = []
    for run, point in placed:
        value = _value(run, objective, options.maximise)
        if value is not None:
            scored.append(Scored(point, value, run.failed, run.assignment))
    notes: tuple[str, ...] = ()
    if placed and not scored:
        notes = (f"no run read recorded '{objective}': the optimiser starts from scratch",)
    proposal = propose_falsify(space, scored, options.samples, options.seed, objective, options.maximise,
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
    if options.threshold is not None and options.objective is None:
        raise SearchError("--threshold needs --objective NAME: the record() item whose values cross it")
    placed = _placed(space, history)
    if options.strategy == "boundary":
        points, estimate, notes = _boundary(space, placed, options)
    elif options.strategy == "falsify":
        points, estimate, notes = _falsify(space, placed, options)
    else:
        points, estimate, notes = _holes(space, history, placed, options)
    number = options.round_number or max(history.last_round, FIRST_ROUND - 1) + 1
    record = RoundRecord(number, options.strategy, options.sources, len(history.runs), estimate,
                         options.objective if options.strategy != "falsify" else options.objective or MARGIN,
                         options.maximise)
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
