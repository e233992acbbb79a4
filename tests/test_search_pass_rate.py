"""``scenario_variation --from RESULTS --strategy boundary --pass-rate R --along KEY``: the level of one varied
parameter where the share of passing runs over the others crosses ``R``, through the real CLIs in a pipe.

The sweep of our own fails when ``noise + drop > 8`` (both listed 0..7), so the pass rate at noise level ``n``
is ``#{drop <= 8 - n} / 8`` by arithmetic: 100 % up to 1, then 7/8, 6/8, 5/8, 4/8 (at 5: not below 50 %), 3/8 at
6: the rate falls below 50 % between noise 5 and 6.
"""

from __future__ import annotations

import json
import random
import subprocess
from pathlib import Path

import pytest
from batch_fixtures import BIN, cli_env, run_cli
from cli_support import run_variation

from coverage_engine.domains import InputDomain
from coverage_engine.proposals import SEARCH_FILE
from coverage_engine.search.pass_rate import RateRun, propose_pass_rate
from coverage_engine.search.space import Space

SWEEP = """import osc.helpers

scenario sweep:
    noise: int with:
        keep(it in [0, 1, 2, 3, 4, 5, 6, 7])
    drop: int with:
        keep(it in [0, 1, 2, 3, 4, 5, 6, 7])
    do serial:
        wait elapsed(0.01s)
        compare(noise + drop, "<=", 8)
"""


def passing_share(noise: float) -> float:
    """The share of drop levels 0..7 that pass at ``noise``."""
    return sum(noise + drop <= 8 for drop in range(8)) / 8


def vary(cwd: Path, *args: str) -> str:
    done = run_variation(cwd, "sweep.osc", *args)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


@pytest.mark.slow
def test_pass_rate_boundary_finds_the_level_where_half_the_runs_fail_in_fewer_runs_than_the_grid(tmp_path):
    (tmp_path / "sweep.osc").write_text(SWEEP)
    vary(tmp_path, "--strategy", "lhs", "--samples", "8", "--seed", "4", "-o", "round1")
    sources: list[str] = []
    runs = 0
    for number in range(1, 8):
        if number > 1:
            out = vary(tmp_path, *sources, "--strategy", "boundary", "--pass-rate", "0.5", "--along", "noise",
                       "--samples", "8", "--seed", str(number), "-o", f"round{number}")
            search = json.loads((tmp_path / f"round{number}" / SEARCH_FILE).read_text())
            if search["estimate"]["done"]:
                break
        proposed = sorted((tmp_path / f"round{number}").glob("*.sce"))
        assert 0 < len(proposed) <= 8
        runs += len(proposed)
        done = run_cli(["-i", f"round{number}", "-o", f"results{number}"], tmp_path, cli_env(tmp_path))
        assert done.returncode in (0, 1), done.stdout + done.stderr
        sources += ["--from", f"results{number}"]
    assert search["estimate"]["done"], out
    boundary = search["estimate"]["boundary"]
    assert boundary["axes"] == {"sweep.noise": {"value": 5.5, "error": 0.5, "unit": ""}}
    assert boundary["pass_rate"]["rate"] == 0.5 and boundary["pass_rate"]["along"] == "sweep.noise"
    for level in boundary["pass_rate"]["levels"]:      # every side decided agrees with the arithmetic
        if level["side"] is not None:
            assert (level["side"] == "above") == (passing_share(level["value"]) >= 0.5), level
        assert level["passed"] <= level["runs"] <= 8
    assert "boundary: noise = 5.5 ± 0.5" in out and "goal met" in out
    sides = {level["value"]: level["side"] for level in boundary["pass_rate"]["levels"]}
    assert sides[5] == "above" and sides[6] == "below"
    assert "pass rate along noise: " in out and "; 6: " in out and "(below 50 %)" in out
    assert runs <= 40, f"{runs} runs (the full grid takes 64)"
    print(f"{runs} runs")


def test_along_names_one_parameter_and_goes_with_pass_rate(tmp_path):
    (tmp_path / "sweep.osc").write_text(SWEEP)
    vary(tmp_path, "--strategy", "lhs", "--samples", "4", "--seed", "1", "-o", "round1")
    assert run_cli(["-i", "round1", "-o", "results1"], tmp_path, cli_env(tmp_path)).returncode in (0, 1)
    cases = [(("--pass-rate", "0.5"), "--pass-rate needs --along KEY"),
             (("--pass-rate", "0.5", "--along", "speed"), "--along speed names none of the varied parameters "
                                                          "(sweep.noise, sweep.drop)"),
             (("--along", "noise"), "--along goes with --pass-rate R")]
    for extra, message in cases:
        done = run_variation(tmp_path, "sweep.osc", "--from", "results1", "--strategy", "boundary", "--samples", "4",
                             *extra, "-o", "round2")
        assert done.returncode == 1 and message in done.stderr, done.stderr
        assert "Traceback" not in done.stderr
    done = run_variation(tmp_path, "sweep.osc", "--from", "results1", "--strategy", "falsify", "--samples", "4",
                         "--pass-rate", "0.5", "--along", "noise", "-o", "round2")
    assert done.returncode == 1 and "--pass-rate is an option of --strategy boundary" in done.stderr


def test_a_continuous_axis_is_bisected_to_the_resolution():
    """noise a range 0..8 (the same rule): the rate is below 50 % exactly when noise > 5."""
    space = Space((InputDomain("noise", low=0.0, high=8.0), InputDomain("drop", values=tuple(range(8)))))

    def passed(point: tuple[float, ...]) -> bool:
        return point[0] * 8 + int(point[1] * 8) <= 8

    rng = random.Random(3)
    runs = [RateRun(p, passed(p)) for p in ((rng.random(), (k + 0.5) / 8) for k in range(8))]
    for number in range(40):
        proposal = propose_pass_rate(space, runs, 0, 0.5, 8, 0.01, number)
        if proposal.boundary.located:
            break
        assert proposal.points and all(p not in {r.point for r in runs} for p in proposal.points)
        runs += [RateRun(p, passed(p)) for p in proposal.points]
    found = proposal.boundary
    assert found.located and found.falling and found.before is not None and found.after is not None
    assert found.before.coordinate * 8 <= 5 < found.after.coordinate * 8 + 1e-9
    assert found.after.coordinate - found.before.coordinate <= 0.01 + 1e-9
    assert len(runs) < 101 * 8 / 4, len(runs)        # a fraction of a grid of the resolution's levels


@pytest.mark.slow
def test_scenario_search_runs_the_pass_rate_boundary_to_the_level_the_arithmetic_gives(tmp_path):
    """The whole loop with --pass-rate/--along: its final estimate is the crossing between noise 5 and 6."""
    (tmp_path / "sweep.osc").write_text(SWEEP)
    done = subprocess.run([str(BIN / "scenario_search"), "sweep.osc", "--goal", "boundary", "--pass-rate", "0.5",
                           "--along", "noise", "--budget", "48", "--round", "8", "--seed", "4", "-j", "2", "-o",
                           "search"], cwd=tmp_path, env=cli_env(tmp_path), capture_output=True, text=True, timeout=600)
    assert done.returncode in (0, 1), done.stdout + done.stderr
    search = json.loads((tmp_path / "search" / SEARCH_FILE).read_text())
    assert search["settings"]["pass_rate"] == 0.5 and search["settings"]["along"] == "noise"
    boundary = search["estimate"]["boundary"]
    assert boundary["axes"] == {"sweep.noise": {"value": 5.5, "error": 0.5, "unit": ""}}, done.stdout
    assert "noise = 5.5 ± 0.5" in done.stdout
