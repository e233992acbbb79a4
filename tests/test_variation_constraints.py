"""Keep conditions as constraints (issue 12, item 2): no strategy writes a variant that breaks one.

The checks here are independent of the generator: the conditions are re-evaluated in Python on the
values each written ``.sce`` holds, and for covering arrays every t-tuple that some valid combination
holds (found by brute force over the small model) must appear in a written variant.
"""

from __future__ import annotations

import itertools
import subprocess
import sys
from pathlib import Path

import yaml
from cli_support import run_variation

ROOT = Path(__file__).resolve().parent.parent

DISCRETE = """import osc.helpers

scenario cut:
    a: int with:
        keep(it in [1, 2, 3, 4])
    b: int with:
        keep(it in [1, 2, 3, 4])
    c: int with:
        keep(it in [1, 2, 3])
    d: int with:
        keep(it in [1, 2, 3])
    keep(a != b)
    keep(not (c == 3 and a == 1))
    keep(d <= c)
    do serial:
        log("x")
"""


def holds(a: int, b: int, c: int, d: int) -> bool:
    """The conditions of DISCRETE, written out independently."""
    return a != b and not (c == 3 and a == 1) and d <= c


def written(folder: Path) -> list[dict]:
    """The assignment of every variant file in ``folder``."""
    return [yaml.safe_load(p.read_text())["assignment"] for p in sorted(folder.glob("*.sce"))]


def values(assignment: dict) -> tuple[int, ...]:
    return tuple(assignment[f"cut.{k}"] for k in "abcd")


def test_full_product_writes_exactly_the_combinations_that_hold(tmp_path):
    (tmp_path / "cut.osc").write_text(DISCRETE)
    done = run_variation(tmp_path, "cut.osc")
    assert done.returncode == 0, done.stderr
    expected = {v for v in itertools.product([1, 2, 3, 4], [1, 2, 3, 4], [1, 2, 3], [1, 2, 3]) if holds(*v)}
    got = [values(a) for a in written(tmp_path / "out")]
    assert sorted(got) == sorted(expected)
    assert f"{len(expected)} combinations (4 x 4 x 3 x 3; {144 - len(expected)} break a keep condition)" \
        in done.stdout
    assert "cut.osc:12:5: condition keep(a != b): rules out 4 of 16 value combination(s) of cut.a, cut.b" \
        in done.stdout
    names = sorted(p.name for p in (tmp_path / "out").glob("*.sce"))
    assert names == sorted(f"cut{i}.sce" for i in range(len(expected)))     # numbered without gaps
    run = subprocess.run([sys.executable, "-m", "cli.scenario_execution", "-n", str(tmp_path / "out" / "cut0.sce")],
                         cwd=tmp_path, capture_output=True, text=True, env={"PYTHONPATH": str(ROOT), "PATH": ""})
    assert run.returncode == 0, run.stderr


def covered_tuples(rows: list[tuple[int, ...]], t: int) -> set:
    return {(axes, tuple(row[a] for a in axes)) for row in rows for axes in itertools.combinations(range(4), t)}


def test_covering_arrays_cover_every_coverable_tuple_and_break_no_condition(tmp_path):
    (tmp_path / "cut.osc").write_text(DISCRETE)
    valid = [v for v in itertools.product([1, 2, 3, 4], [1, 2, 3, 4], [1, 2, 3], [1, 2, 3]) if holds(*v)]
    for t, args in ((2, ["--strategy", "pairwise"]), (3, ["--strategy", "t-way", "--strength", "3"])):
        out = tmp_path / f"out{t}"
        done = run_variation(tmp_path, "cut.osc", *args, "--seed", "5", "-o", str(out))
        assert done.returncode == 0, done.stderr
        rows = [values(a) for a in written(out)]
        assert all(holds(*row) for row in rows), "a written variant breaks a keep condition"
        coverable = covered_tuples(valid, t)
        assert coverable <= covered_tuples(rows, t), "a coverable tuple is not covered"
        assert len(rows) < len(valid)
        assert f"{len(coverable)} of {len(coverable)} coverable {t}-tuples covered" in done.stdout


SAMPLED = """import osc.helpers

scenario drive:
    speed: speed with:
        keep(it in [10kph..90kph])
    gap: length with:
        keep(it in [5m..50m])
    lane: int with:
        keep(it in [1, 2, 3])
    keep(speed < 60kph)
    keep(not (lane == 3 and gap < 20m))
    do serial:
        log("x")
"""


def number(value: object) -> float:
    """A drawn value as stored (a number in the range's unit) or a listed one as text (``30kph``)."""
    return float(value) if isinstance(value, (int, float)) else float(str(value).rstrip("kphm"))


def test_samplers_redraw_until_every_variant_holds_and_stay_reproducible(tmp_path):
    (tmp_path / "drive.osc").write_text(SAMPLED)
    for strategy in ("lhs", "random", "halton"):
        out = tmp_path / strategy
        done = run_variation(tmp_path, "drive.osc", "--strategy", strategy, "--samples", "40", "--seed", "9",
                             "-o", str(out))
        assert done.returncode == 0, done.stderr
        rows = written(out)
        assert len(rows) == 40
        for row in rows:
            assert number(row["drive.speed"]) < 60
            assert not (row["drive.lane"] == 3 and number(row["drive.gap"]) < 20)
    again = run_variation(tmp_path, "drive.osc", "--strategy", "lhs", "--samples", "40", "--seed", "9",
                          "-o", str(tmp_path / "again"))
    assert again.returncode == 0
    first = {p.name: p.read_bytes() for p in (tmp_path / "lhs").glob("*.sce")}
    second = {p.name: p.read_bytes() for p in (tmp_path / "again").glob("*.sce")}
    assert first.keys() == second.keys()
    assert all(first[n].split(b"source_sha256")[1] == second[n].split(b"source_sha256")[1] for n in first)


def test_a_sampler_whose_draws_all_fail_names_the_condition(tmp_path):
    (tmp_path / "drive.osc").write_text(SAMPLED.replace("keep(speed < 60kph)", "keep(speed > 89.99kph)"))
    done = run_variation(tmp_path, "drive.osc", "--strategy", "random", "--samples", "5", "--seed", "1")
    assert done.returncode == 1
    assert "Traceback" not in done.stderr
    assert "drawn variants satisfy the keep conditions" in done.stderr
    assert "keep(speed > 89.99kph) left out" in done.stderr
    assert "drive.osc:10:5" in done.stderr
    assert not list((tmp_path / "out").glob("*.sce")) if (tmp_path / "out").exists() else True


def test_a_condition_no_value_can_meet_is_a_located_error(tmp_path):
    (tmp_path / "cut.osc").write_text(DISCRETE.replace("keep(d <= c)", "keep(d > 7)"))
    done = run_variation(tmp_path, "cut.osc")
    assert done.returncode == 1
    assert "cut.osc:14:5: error: no variant satisfies keep: keep(d > 7)" in done.stderr
    assert "Traceback" not in done.stderr


def test_conditions_on_a_parameter_and_on_an_invocation(tmp_path):
    (tmp_path / "p.osc").write_text("""import osc.helpers

scenario p:
    gap: length with:
        keep(it in [1m, 2m, 3m, 4m])
        keep(it >= 2m)
    do serial:
        log() with:
            keep(it.msg in ['A', 'B', 'C'])
            keep(it.msg != 'B')
""")
    done = run_variation(tmp_path, "p.osc")
    assert done.returncode == 0, done.stderr
    got = sorted((a["p.gap"], a["p.log.msg"]) for a in written(tmp_path / "out"))
    assert got == sorted(itertools.product(["2m", "3m", "4m"], ["A", "C"]))


def run_scenario(tmp_path: Path, text: str) -> subprocess.CompletedProcess:
    (tmp_path / "s.osc").write_text(text)
    return subprocess.run([sys.executable, "-m", "cli.scenario_execution", "-n", "s.osc"], cwd=tmp_path,
                          capture_output=True, text=True, env={"PYTHONPATH": str(ROOT), "PATH": ""})


def test_scenario_execution_checks_conditions_where_they_are_written(tmp_path):
    base = """import osc.helpers

scenario s:
    start: length = 2m with:
        keep(it >= 1m)
    goal: length = GOAL
    keep(goal > start)
    do serial:
        log() with:
            keep(it.msg == 'ok')
            keep(it.msg != 'bad')
"""
    assert run_scenario(tmp_path, base.replace("GOAL", "5m")).returncode == 0
    broken = run_scenario(tmp_path, base.replace("GOAL", "1m"))
    assert broken.returncode == 1
    assert broken.stderr.startswith("s.osc:7:5: error: constraint does not hold: keep(goal > start)")
    broken = run_scenario(tmp_path, base.replace("GOAL", "5m").replace("= 2m with", "= 0.5m with"))
    assert broken.stderr.startswith("s.osc:5:9: error: constraint does not hold: keep(it >= 1m)")
    broken = run_scenario(tmp_path, base.replace("GOAL", "5m").replace("== 'ok'", "== 'bad'"))
    assert broken.stderr.startswith("s.osc:11:13: error: constraint does not hold: keep(it.msg != 'bad')")
    ordered = run_scenario(tmp_path, base.replace("GOAL", "5m").replace("!= 'bad'", "<= 'z'"))
    assert ordered.returncode == 1 and "cannot order strings" in ordered.stderr


def test_a_condition_among_an_actors_members_is_refused(tmp_path):
    done = run_scenario(tmp_path, "import osc.helpers\nactor car:\n    position: float\n    keep(position < 100.0)\n"
                                  "scenario s:\n    do log('x')\n")
    assert done.returncode == 1
    assert done.stderr.startswith("s.osc:4:5: error: not supported: a keep condition among the members of actor 'car'")


def test_the_store_keeps_what_a_covering_array_covered(tmp_path):
    import json
    import sqlite3

    (tmp_path / "cut.osc").write_text(DISCRETE)
    done = run_variation(tmp_path, "cut.osc", "--strategy", "pairwise", "--seed", "2")
    assert done.returncode == 0, done.stderr
    with sqlite3.connect(tmp_path / ".scenario_store.db") as db:
        (options,) = db.execute("SELECT options FROM variation_runs").fetchone()
    recorded = json.loads(options)
    assert recorded["strategy"] == "pairwise" and recorded["seed"] == 2
    tuples = recorded["tuples"]
    assert tuples["covered"] == tuples["coverable"] and tuples["strength"] == 2
    assert f"{tuples['covered']} of {tuples['coverable']} coverable 2-tuples covered ({tuples['impossible']} impossible" \
        in done.stdout
    assert recorded["variants"] == len(list((tmp_path / "out").glob("*.sce")))
