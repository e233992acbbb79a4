"""``scenario_variation --from RESULTS --strategy boundary|falsify|fill-holes`` (issue 35 items 1-4), through the
real CLIs in a pipe: variants written, run by the real batch runner, read back, proposed again.

The braking scenario's answer is known by arithmetic: the car fails to stop when
``speed² / (2·decel) + speed·reaction > gap`` (its ``compare`` check fails then), so where each proposal
lies with respect to the true boundary, and whether a failing variant exists, can be checked exactly.
"""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import pytest
import yaml
from batch_fixtures import cli_env, run_cli
from cli_support import run_variation

from coverage_engine.proposals import SEARCH_FILE, SEARCH_FORMAT, header_proposal

pytestmark = pytest.mark.slow

SPEED, DECEL, REACTION = (10.0, 40.0), (2.0, 10.0), 1.0


def braking(gap: float, speed: tuple[float, float] = SPEED, decel: tuple[float, float] = DECEL) -> str:
    return f"""import osc.helpers

scenario brake:
    speed: float = {speed[0]} with:
        keep(it in [{speed[0]}..{speed[1]}])
    decel: float = {decel[0]} with:
        keep(it in [{decel[0]}..{decel[1]}])
    reaction: float = {REACTION}
    gap: float = {gap}
    record(min_gap, expression: gap - (speed * speed / (2.0 * decel) + speed * reaction), event: finish)
    do serial:
        wait elapsed(0.01s)
        compare(speed * speed / (2.0 * decel) + speed * reaction, "<=", gap)
"""


def vary(cwd: Path, *args: str) -> str:
    done = run_variation(cwd, "brake.osc", *args)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def batch(cwd: Path, variants: str, results: str) -> None:
    done = run_cli(["-i", variants, "-o", results], cwd, cli_env(cwd))
    assert done.returncode in (0, 1), done.stdout + done.stderr     # 1: some variant failed, as expected


def assignments(folder: Path) -> list[dict]:
    return [yaml.safe_load(path.read_text())["assignment"] for path in sorted(folder.glob("*.sce"))]


def critical_speed(decel: float, gap: float) -> float:
    """The speed at which the car stops exactly at the obstacle (s²/(2d) + s·r = gap)."""
    return -REACTION * decel + math.sqrt((REACTION * decel) ** 2 + 2 * decel * gap)


def distance_to_boundary(speed: float, decel: float, gap: float) -> float:
    """Distance from a run to the true boundary in the unit square (each range scaled to 1)."""
    u = ((speed - SPEED[0]) / (SPEED[1] - SPEED[0]), (decel - DECEL[0]) / (DECEL[1] - DECEL[0]))
    best = math.inf
    for k in range(2001):
        d = DECEL[0] + k / 2000 * (DECEL[1] - DECEL[0])
        s = (critical_speed(d, gap) - SPEED[0]) / (SPEED[1] - SPEED[0])
        best = min(best, math.hypot(u[0] - s, u[1] - k / 2000))
    return best


def test_boundary_places_most_of_its_runs_near_the_true_boundary_round_after_round(tmp_path):
    gap = 80.0
    (tmp_path / "brake.osc").write_text(braking(gap))
    vary(tmp_path, "--strategy", "lhs", "--samples", "20", "--seed", "5", "-o", "round1")
    batch(tmp_path, "round1", "results1")
    proposed: list[dict] = []
    pairs = []
    for number in range(2, 6):
        sources = [arg for k in range(1, number) for arg in ("--from", f"results{k}")]
        out = vary(tmp_path, *sources, "--strategy", "boundary", "--samples", "10", "--seed", str(number),
                   "-o", f"round{number}")
        assert f"round {number}, strategy boundary: {10 * (number - 1) + 10} earlier run(s) read" in out
        assert "pair(s) of neighbouring runs disagree" in out
        folder = tmp_path / f"round{number}"
        search = json.loads((folder / SEARCH_FILE).read_text())
        assert search["format"] == SEARCH_FORMAT and search["round"] == number and search["strategy"] == "boundary"
        assert search["from"] == [f"results{k}" for k in range(1, number)] and search["runs_read"] == 10 * number
        assert search["estimate"]["worst"] is None and not search["estimate"]["done"]
        pairs.append(search["estimate"]["boundary"]["pairs"])
        first = next(folder.glob("*.sce")).read_text()
        proposal = header_proposal(first)
        assert proposal is not None and proposal.round == number and proposal.strategy == "boundary"
        rows = assignments(folder)
        assert len(rows) == 10
        proposed += rows
        batch(tmp_path, f"round{number}", f"results{number}")
    near = [distance_to_boundary(row["brake.speed"], row["brake.decel"], gap) <= 0.05 for row in proposed]
    assert sum(near) >= 0.8 * len(proposed), f"{sum(near)} of {len(proposed)} runs within 5 % of the boundary"
    # later rounds see more of the boundary: more pairs of neighbouring runs that disagree
    assert pairs[0] < pairs[-1], pairs


def test_boundary_in_one_dimension_prints_the_value_and_stops_when_located(tmp_path):
    gap = 80.0
    decel = 4.0
    (tmp_path / "brake.osc").write_text(braking(gap, decel=(decel, decel + 1e-9)).replace(
        f"keep(it in [{decel}..{decel + 1e-9}])", f"keep(it == {decel})"))
    vary(tmp_path, "--strategy", "lhs", "--samples", "6", "--seed", "2", "-o", "round1")
    batch(tmp_path, "round1", "results1")
    sources = ["--from", "results1"]
    for number in range(2, 12):
        out = vary(tmp_path, *sources, "--strategy", "boundary", "--samples", "3", "--resolution", "0.01",
                   "--seed", "1", "-o", f"round{number}")
        search = json.loads((tmp_path / f"round{number}" / SEARCH_FILE).read_text())
        if search["estimate"]["done"]:
            break
        batch(tmp_path, f"round{number}", f"results{number}")
        sources += ["--from", f"results{number}"]
    assert search["estimate"]["done"], out
    axis = search["estimate"]["boundary"]["axes"]["brake.speed"]
    truth = critical_speed(decel, gap)
    assert abs(axis["value"] - truth) <= axis["error"] <= 0.01 * (SPEED[1] - SPEED[0]) / 2 + 1e-9
    assert f"boundary: speed = {axis['value']:.4g} ± " in out and "goal met" in out
    assert "no variant proposed: the goal is met" in out and not list((tmp_path / f"round{number}").glob("*.sce"))


@pytest.mark.parametrize("objective", ["min_gap", "margin"])
def test_falsify_finds_a_failing_variant_the_first_round_missed(tmp_path, objective):
    """``min_gap`` is the scenario's record() item; ``margin`` how close its compare check came to flipping,
    which every run reports (the scenario's record() line is taken out for it)."""
    gap = 125.0                       # only a corner fails: speed above about 28 m/s with decel under 4.7 m/s²
    text = braking(gap, speed=(10.0, 30.0), decel=(4.0, 10.0))
    if objective == "margin":
        text = "\n".join(line for line in text.splitlines() if "record(" not in line) + "\n"
    (tmp_path / "brake.osc").write_text(text)
    vary(tmp_path, "--strategy", "lhs", "--samples", "8", "--seed", "3", "-o", "round1")
    batch(tmp_path, "round1", "results1")
    rows = assignments(tmp_path / "round1")
    assert all(critical_speed(r["brake.decel"], gap) >= r["brake.speed"] for r in rows), "round 1 already failed"
    sources = ["--from", "results1"]
    found = None
    for number in range(2, 8):
        chosen = ("--objective", objective) if objective == "min_gap" else ()     # margin: the default
        out = vary(tmp_path, *sources, "--strategy", "falsify", *chosen, "--samples", "8",
                   "--seed", "7", "-o", f"round{number}")
        assert f"worst case: {objective} = " in out
        search = json.loads((tmp_path / f"round{number}" / SEARCH_FILE).read_text())
        assert search["objective"] == objective and search["maximise"] is False
        worst = search["estimate"]["worst"]
        if worst["failed"]:
            found = worst
            break
        rows = assignments(tmp_path / f"round{number}")
        assert len(rows) == 8
        batch(tmp_path, f"round{number}", f"results{number}")
        sources += ["--from", f"results{number}"]
    assert found is not None, "no failing variant within 6 rounds of 8"
    assert found["value"] < 0 and search["estimate"]["done"] and "goal met" in out
    speed, decel = found["assignment"]["brake.speed"], found["assignment"]["brake.decel"]
    assert speed * speed / (2 * decel) + speed * REACTION > gap


LANES = """import osc.helpers

scenario road:
    lanes: int with:
        keep(it in [1, 2, 3])
    weather: string with:
        keep(it in ["dry", "wet", "snow"])
    cover(lanes, range: [0..6], every: 2)
    do serial:
        log(weather)
"""


def test_fill_holes_proposes_exactly_the_missing_cells_of_a_partly_run_cross(tmp_path):
    (tmp_path / "road.osc").write_text(LANES)
    done = run_variation(tmp_path, "road.osc", "-o", "round1")
    assert done.returncode == 0, done.stderr
    all_cells = {(r["road.lanes"], r["road.weather"]) for r in assignments(tmp_path / "round1")}
    assert len(all_cells) == 9
    for name in ("road1.sce", "road3.sce", "road5.sce", "road7.sce"):      # 4 of 9 cells never run
        (tmp_path / "round1" / name).unlink()
    ran = {(r["road.lanes"], r["road.weather"]) for r in assignments(tmp_path / "round1")}
    batch(tmp_path, "round1", "results1")
    done = run_variation(tmp_path, "road.osc", "--from", "results1", "--strategy", "fill-holes", "--samples", "4",
                         "--seed", "1", "-o", "round2")
    assert done.returncode == 0, done.stdout + done.stderr
    proposed = [(r["road.lanes"], r["road.weather"]) for r in assignments(tmp_path / "round2")]
    assert sorted(proposed) == sorted(all_cells - ran)
    search = json.loads((tmp_path / "round2" / SEARCH_FILE).read_text())
    assert search["estimate"]["holes"] == {"targeted": 4, "guessed": 0} and not search["estimate"]["done"]
    # more samples than input holes: the rest aim at the measured item's empty buckets (4..5 and 6), as a guess
    done = run_variation(tmp_path, "road.osc", "--from", "results1", "--strategy", "fill-holes", "--samples", "6",
                         "--seed", "1", "-o", "round2b")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "note: a guess: aiming at lanes 4..5 near the run whose value came closest" in done.stdout
    assert "lanes 6 near" in done.stdout and len(assignments(tmp_path / "round2b")) == 6
    search = json.loads((tmp_path / "round2b" / SEARCH_FILE).read_text())
    assert search["estimate"]["holes"] == {"targeted": 4, "guessed": 2}
    batch(tmp_path, "round2", "results2")
    done = run_variation(tmp_path, "road.osc", "--from", "results1", "--from", "results2", "--strategy", "fill-holes",
                         "--samples", "4", "--seed", "1", "-o", "round3")
    assert done.returncode == 0, done.stdout + done.stderr
    search = json.loads((tmp_path / "round3" / SEARCH_FILE).read_text())
    # every cell of the inputs is run now; only the measured item's buckets, out of reach, are guessed at again
    assert search["estimate"]["holes"] == {"targeted": 0, "guessed": 2} and not search["estimate"]["done"]
    assert len(assignments(tmp_path / "round3")) == 2


def test_adaptive_strategies_and_from_go_together_and_errors_are_located(tmp_path):
    (tmp_path / "brake.osc").write_text(braking(80.0))
    done = run_variation(tmp_path, "brake.osc", "--strategy", "boundary", "--samples", "4")
    assert done.returncode == 1 and "needs" not in done.stdout
    assert "brake.osc: error: --strategy boundary proposes from earlier results: give them with --from" in done.stderr
    done = run_variation(tmp_path, "brake.osc", "--strategy", "lhs", "--samples", "4", "--from", "nowhere")
    assert done.returncode == 1 and "--from is read by the adaptive strategies" in done.stderr
    done = run_variation(tmp_path, "brake.osc", "--strategy", "boundary", "--samples", "4", "--from", "nowhere")
    assert done.returncode == 1 and "nowhere: error: no such folder" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_first_round_with_a_round_number_writes_the_proposal_line(tmp_path):
    (tmp_path / "brake.osc").write_text(braking(80.0))
    vary(tmp_path, "--strategy", "lhs", "--samples", "3", "--seed", "1", "--round", "1", "-o", "round1")
    proposal = header_proposal(next((tmp_path / "round1").glob("*.sce")).read_text())
    assert proposal is not None and (proposal.round, proposal.strategy, proposal.sources) == (1, "lhs", ())


def test_pipe_output_of_a_round_is_plain_text(tmp_path):
    (tmp_path / "brake.osc").write_text(braking(80.0))
    vary(tmp_path, "--strategy", "lhs", "--samples", "6", "--seed", "1", "-o", "round1")
    batch(tmp_path, "round1", "results1")
    out = subprocess.run([*_variation(), "brake.osc", "--from", "results1", "--strategy", "boundary", "--samples", "4",
                          "--seed", "1", "-o", "round2"], cwd=tmp_path, capture_output=True, text=True,
                         env=cli_env(tmp_path)).stdout
    assert "\x1b[" not in out and out.startswith("round 2, strategy boundary: 6 earlier run(s) read\n")


def _variation() -> list[str]:
    import sys

    return [str(Path(sys.executable).parent / "scenario_variation")]
