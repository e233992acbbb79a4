"""The proposal algorithms of the adaptive strategies as pure functions (issue 35 items 2-4): the unit cube,
bisection towards the boundary, the holes of the inputs and their crosses, Optuna's ask/tell rounds, and the
round's ``search.json`` document. The same strategies through the real CLIs: ``test_search_strategies.py``."""

from __future__ import annotations

import json
import math

import pytest

from coverage_engine.coverage.run_records import ItemDecl
from coverage_engine.coverage.values import ValueType
from coverage_engine.domains import InputDomain
from coverage_engine.proposals import SEARCH_FORMAT
from coverage_engine.search.boundary import Observation, neighbour_pairs, propose_boundary
from coverage_engine.search.errors import SearchError
from coverage_engine.search.estimate import (
    RoundRecord,
    estimate_lines,
    round_dict,
    round_heading,
    write_round,
)
from coverage_engine.search.falsify import Scored, propose_falsify
from coverage_engine.search.history import History, PastRun
from coverage_engine.search.holes import propose_holes
from coverage_engine.search.propose import SearchOptions, propose_round
from coverage_engine.search.space import Space, coordinate_of
from coverage_engine.search.surface import fit_surface
from coverage_engine.search.target import SearchTarget

SPEED = InputDomain("t.speed", low=10.0, high=50.0, unit="kph")
LANES = InputDomain("t.lanes", values=(1, 2, 3))
WEATHER = InputDomain("t.weather", values=("dry", "wet", "snow"))


def test_a_value_sits_where_design_points_maps_the_coordinate_back():
    space = Space((SPEED, LANES))
    assert space.point_of({"t.speed": 30.0, "t.lanes": 3}) == (0.5, 2.5 / 3)
    assert space.point_of({"t.speed": "30kph", "t.lanes": 1}) == (0.5, 0.5 / 3)
    assert space.value_at(0, 0.25) == 20.0 and space.value_at(1, 0.99) == 3 and space.value_at(1, 0.0) == 1
    assert space.point_of({"t.speed": 60.0, "t.lanes": 1}) is None      # outside the declared range
    assert space.point_of({"t.speed": 30.0}) is None and coordinate_of(LANES, 4) is None
    assert space.snap((1.4, 0.4)) == (1.0, 1.5 / 3)


def one_dimensional_runs(flip: float, points: list[float]) -> list[Observation]:
    return [Observation((u,), u > flip, {"t.speed": 10.0 + 40.0 * u}) for u in points]


def test_bisection_in_one_dimension_locates_the_flip_to_the_resolution_and_then_stops():
    space = Space((SPEED,))
    flip = 0.3721
    runs = one_dimensional_runs(flip, [0.1, 0.5, 0.9])
    for _ in range(20):
        proposal = propose_boundary(space, runs, 3, 0.01, seed=1)
        if proposal.done:
            break
        assert len(proposal.points) == 3
        runs += one_dimensional_runs(flip, [p[0] for p in proposal.points])
    assert proposal.done and proposal.points == ()
    axis = proposal.estimate.axes["t.speed"]
    assert axis.unit == "kph" and abs(axis.value - (10.0 + 40.0 * flip)) <= axis.error <= 0.01 * 40 / 2
    assert len(runs) <= 3 + 3 * 4           # 1/4 -> 1/16 -> 1/64 -> 1/256 of the range: 4 rounds of 3


def test_only_neighbouring_runs_that_disagree_with_nothing_between_them_are_pairs():
    space = Space((SPEED, SPEED))
    runs = [Observation((0.1, 0.5), False, {}), Observation((0.9, 0.5), True, {}),
            Observation((0.5, 0.5), False, {})]
    pairs = neighbour_pairs(space, runs, 0.01)
    assert [(p.first, p.second) for p in pairs] == [(1, 2)]   # (0, 1) has run 2 in between
    assert math.isclose(pairs[0].length, 0.4) and not pairs[0].located


def test_before_anything_failed_boundary_fills_the_space_and_says_it_has_not_seen_the_boundary():
    space = Space((SPEED, LANES))
    runs = [Observation((0.5, 0.5), False, {})]
    proposal = propose_boundary(space, runs, 5, 0.01, seed=3)
    assert len(set(proposal.points)) == 5 and not proposal.done and proposal.estimate.pairs == 0
    assert proposal == propose_boundary(space, runs, 5, 0.01, seed=3)          # a function of the seed
    assert all(p[1] in (0.5 / 3, 1.5 / 3, 2.5 / 3) for p in proposal.points)    # a listed axis: its values' centres


def test_the_fitted_surface_separates_a_quadratic_boundary():
    points = [(x / 7, y / 7) for x in range(8) for y in range(8)]
    failing = [x * x + y > 0.8 for x, y in points]
    surface = fit_surface(points, failing)
    assert surface is not None
    assert sum((surface.score(p) > 0) == f for p, f in zip(points, failing, strict=True)) >= 62
    t = surface.crossing((0.0, 0.0), (1.0, 1.0))
    assert t is not None and abs(t - (math.sqrt(4.2) - 1) / 2) < 0.05      # t² + t = 0.8
    assert fit_surface(points, [False] * len(points)) is None


def test_fill_holes_proposes_the_missing_cells_of_a_cross_and_nothing_else():
    space = Space((LANES, WEATHER))
    ran = [(1, "dry"), (2, "wet"), (3, "snow"), (1, "wet"), (2, "dry")]
    assignments = [{"t.lanes": a, "t.weather": b} for a, b in ran]
    points = [space.point_of(a) for a in assignments]
    proposal = propose_holes(space, points, assignments, 10, seed=1)
    cells = sorted((space.value_at(0, p[0]), space.value_at(1, p[1])) for p in proposal.points)
    assert cells == sorted({(a, b) for a in (1, 2, 3) for b in ("dry", "wet", "snow")} - set(ran))
    assert proposal.holes.targeted == 4 and proposal.holes.guessed == 0 and not proposal.done
    fewer = propose_holes(space, points, assignments, 2, seed=1)
    assert len(fewer.points) == 2 and fewer.holes.targeted == 2


def test_fill_holes_aims_at_empty_range_buckets_and_guesses_near_the_closest_run_for_measured_items():
    space = Space((InputDomain("t.speed", low=0.0, high=100.0, samples=20),))      # 10 buckets of 10
    assignments = [{"t.speed": v} for v in (5.0, 15.0, 25.0, 35.0, 45.0, 55.0, 65.0, 75.0, 85.0)]
    points = [space.point_of(a) for a in assignments]
    measured = ItemDecl("gap", "cover", "t", ValueType("float"), range=(0.0, 4.0), every=1.0)
    samples = [(p, [a["t.speed"] / 30]) for p, a in zip(points, assignments, strict=True)]   # 0.17 .. 2.8
    proposal = propose_holes(space, points, assignments, 3, seed=2, measured=[(measured, samples)])
    assert 0.9 <= proposal.points[0][0] <= 1.0                      # the empty bucket [90..100]
    assert proposal.holes.targeted == 1 and proposal.guessed == ("gap [3..4]",)
    assert abs(proposal.points[1][0] - 0.85) < 0.25                 # near the run that measured most (85 kph)


def braking_value(point: tuple[float, ...]) -> float:
    speed, decel = 10.0 + 20.0 * point[0], 4.0 + 6.0 * point[1]
    return 125.0 - (speed * speed / (2 * decel) + speed)


def test_falsify_asks_optuna_from_the_rebuilt_study_and_finds_the_failing_corner():
    pytest.importorskip("optuna", reason="the search extra is installed by .ci/run")
    space = Space((InputDomain("b.speed", low=10.0, high=30.0), InputDomain("b.decel", low=4.0, high=10.0)))
    grid = [((i + 0.5) / 3, (j + 0.5) / 3) for i in range(3) for j in range(3)]
    scored = [Scored(p, braking_value(p), braking_value(p) < 0, {}) for p in grid]
    assert not any(s.failed for s in scored)
    first = propose_falsify(space, scored, 8, seed=4, objective="min_gap")
    assert first.points == propose_falsify(space, scored, 8, seed=4, objective="min_gap").points   # seeded
    assert first.worst is not None and first.worst.value == min(s.value for s in scored) and not first.done
    for round_number in range(8):
        proposal = propose_falsify(space, scored, 8, seed=round_number, objective="min_gap")
        scored += [Scored(p, braking_value(p), braking_value(p) < 0, {}) for p in proposal.points]
        if any(s.failed for s in scored):
            break
    assert any(s.failed for s in scored), "TPE found no failing variant in 8 rounds of 8"
    last = propose_falsify(space, scored, 1, seed=0, objective="min_gap", any_failed=True)
    assert last.done and last.worst is not None and last.worst.failed and last.worst.value < 0


def test_a_round_numbers_itself_after_the_runs_read_and_keeps_its_estimate_in_the_contract_schema(tmp_path):
    space = Space((SPEED,))
    runs = tuple(PastRun(f"r{i}", "failed" if u > 0.5 else "passed", {"t.speed": 10.0 + 40.0 * u}, round=k)
                 for i, (u, k) in enumerate([(0.2, 1), (0.7, 1), (0.6, 2)]))
    options = SearchOptions("boundary", 2, 1, ("results1", "results2"))
    proposal = propose_round(space, History(runs), options)
    assert proposal.record.round == 3 and len(proposal.points) == 2
    document = round_dict(proposal.record)
    assert set(document) == {"format", "round", "strategy", "from", "runs_read", "objective", "maximise", "estimate"}
    assert document["format"] == SEARCH_FORMAT and document["from"] == ["results1", "results2"]
    assert set(document["estimate"]) == {"boundary", "worst", "holes", "done"}
    assert document["estimate"]["boundary"]["axes"]["t.speed"] == {"value": 26.0, "error": 8.0, "unit": "kph"}
    written = json.loads(write_round(tmp_path, "search.json", proposal.record).read_text())
    assert written == document
    assert estimate_lines(proposal.record.estimate)[0] == "boundary: speed = 26 ± 8 kph"
    assert round_heading(RoundRecord(3, "boundary", (), 3, proposal.record.estimate)) == \
        "round 3, strategy boundary: 3 earlier run(s) read"
    again = propose_round(space, History(runs), SearchOptions("boundary", 2, 1, (), round_number=7))
    assert again.record.round == 7


def test_a_compare_check_says_how_far_it_was_from_flipping_relative_to_its_values():
    from executor.actions.compare import check_margin

    assert check_margin("<=", 132.0, 80.0) == pytest.approx(-52 / 132)
    assert check_margin("<", 40, 80) == pytest.approx(0.5) and check_margin(">=", 2.0, 1.0) == pytest.approx(0.5)
    assert check_margin(">", 0.0, 0.0) == 0.0
    assert check_margin("==", 1.0, 1.0) is None and check_margin("<", "a", "b") is None
    assert check_margin("<", True, 2) is None


def test_boundary_with_a_threshold_splits_the_runs_by_a_record_value_instead_of_their_verdict():
    space = Space((SPEED,))
    runs = tuple(PastRun(f"r{i}", "passed", {"t.speed": 10.0 + 40.0 * u}, {"ttc": (3.0 - 4.0 * u,)})
                 for i, u in enumerate([0.1, 0.3, 0.6, 0.9]))     # every run passed; ttc falls below 1 s past u = 0.5
    options = SearchOptions("boundary", 1, 1, (), SearchTarget(objective="ttc", threshold=1.0))
    proposal = propose_round(space, History(runs), options)
    axis = proposal.record.estimate.boundary.axes["t.speed"]
    assert (axis.value, axis.error) == (28.0, 6.0) and proposal.record.objective == "ttc"
    assert len(proposal.points) == 1 and 0.33 <= proposal.points[0][0] <= 0.57   # inside the pair, off its ends
    verdicts = propose_round(space, History(runs), SearchOptions("boundary", 1, 1, ()))
    assert verdicts.record.estimate.boundary.pairs == 0      # by verdict nothing flips
    with pytest.raises(SearchError, match="--threshold needs --objective"):
        propose_round(space, History(runs), SearchOptions("boundary", 1, 1, (), SearchTarget(threshold=1.0)))
