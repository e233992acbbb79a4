"""scenario_variation --strategy: covering arrays, seeded samples and ranges, through the real CLI (issue 12).

The checks here do not use the generator's code: the values of each dimension are written out in the
test, and every pair (or triple) is looked for in the written ``.sce`` files' assignments.
"""

from __future__ import annotations

import itertools
import subprocess
from pathlib import Path

import pytest
from cli_support import run_variation

from coverage_engine.domains import drawn_text
from coverage_engine.files.sce import read_sce

FIVE = {"a": [0, 1, 2, 3, 4], "b": [0, 1, 2, 3, 4], "c": [0, 1, 2, 3, 4], "d": [0, 1, 2, 3],
        "e": ["x", "y", "z"]}


def vary(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    return run_variation(tmp_path, *args, timeout=120)


def discrete_file(tmp_path: Path) -> Path:
    lines = ["import osc.helpers", "", "scenario m:"]
    for name, values in FIVE.items():
        kind = "string" if isinstance(values[0], str) else "int"
        default = '"x"' if kind == "string" else "0"
        listed = "[0..4]" if values == [0, 1, 2, 3, 4] else \
            "range(0, 3, 1)" if values == [0, 1, 2, 3] else "[" + ", ".join(f'"{v}"' for v in values) + "]"
        lines += [f"    {name}: {kind} = {default} with:", f"        keep(it in {listed})"]
    lines += ["    do serial:", "        log(a)", ""]
    path = tmp_path / "m.osc"
    path.write_text("\n".join(lines))
    return path


def assignments(folder: Path) -> list[dict[str, object]]:
    return [{k.split(".")[-1]: v for k, v in read_sce(p).assignment.items()} for p in sorted(folder.glob("*.sce"))]


def missing_tuples(rows: list[dict[str, object]], t: int) -> list[tuple]:
    missing = []
    for names in itertools.combinations(FIVE, t):
        seen = {tuple(row[n] for n in names) for row in rows}
        for values in itertools.product(*(FIVE[n] for n in names)):
            if values not in seen:
                missing.append((names, values))
    return missing


@pytest.mark.parametrize(("args", "t"), [(("--strategy", "pairwise"), 2),
                                         (("--strategy", "t-way", "--strength", "3"), 3)])
def test_covering_arrays_cover_every_tuple_in_far_fewer_variants(tmp_path, args, t):
    discrete_file(tmp_path)
    done = vary(tmp_path, "m.osc", *args, "--seed", "4")
    assert done.returncode == 0, done.stderr
    rows = assignments(tmp_path / "out")
    assert missing_tuples(rows, t) == []
    full = 5 * 5 * 5 * 4 * 3
    assert len(rows) < full / (4 if t == 2 else 2)
    assert len({tuple(sorted(r.items())) for r in rows}) == len(rows)          # no variant twice
    assert f"coverable {t}-tuples covered" in done.stdout


def test_the_same_seed_gives_the_same_files_byte_for_byte(tmp_path):
    discrete_file(tmp_path)
    for folder, seed in (("one", "7"), ("two", "7"), ("three", "8")):
        assert vary(tmp_path, "m.osc", "--strategy", "pairwise", "--seed", seed, "-o", folder).returncode == 0
    one = {p.name: p.read_bytes() for p in (tmp_path / "one").glob("*.sce")}
    two = {p.name: p.read_bytes() for p in (tmp_path / "two").glob("*.sce")}
    three = {p.name: p.read_bytes() for p in (tmp_path / "three").glob("*.sce")}
    assert one == two
    assert one != three


def test_a_seed_is_chosen_printed_and_reusable(tmp_path):
    discrete_file(tmp_path)
    done = vary(tmp_path, "m.osc", "--strategy", "random", "--samples", "5", "-o", "first")
    assert done.returncode == 0, done.stderr
    seed = done.stdout.split("seed ", 1)[1].split(" ", 1)[0]
    again = vary(tmp_path, "m.osc", "--strategy", "random", "--samples", "5", "--seed", seed, "-o", "second")
    assert again.returncode == 0
    assert assignments(tmp_path / "first") == assignments(tmp_path / "second")


CONTINUOUS = """import osc.helpers

scenario r:
    v: speed = 10kph with:
        keep(it in [10kph..30kph])
    g: float = 1.0 with:
        keep(it in range(0.5, 2.5))
    mode: string = "a" with:
        keep(it in ["a", "b", "c"])
    do serial:
        log(v)
"""


@pytest.mark.parametrize("strategy", ["lhs", "random", "halton"])
def test_samplers_draw_continuous_ranges_inside_their_ends(tmp_path, strategy):
    (tmp_path / "r.osc").write_text(CONTINUOUS)
    done = vary(tmp_path, "r.osc", "--strategy", strategy, "--samples", "20", "--seed", "3")
    assert done.returncode == 0, done.stderr
    rows = assignments(tmp_path / "out")
    assert len(rows) == 20
    speeds = [float(r["v"]) for r in rows]
    gaps = [float(r["g"]) for r in rows]
    assert all(10 <= s <= 30 for s in speeds) and all(0.5 <= g <= 2.5 for g in gaps)
    assert {r["mode"] for r in rows} <= {"a", "b", "c"}
    if strategy == "lhs":          # one value in each of the 20 equal strata of each range
        assert sorted(int((s - 10) / 20 * 20) for s in speeds) == list(range(20))
        assert sorted(int((g - 0.5) / 2 * 20) for g in gaps) == list(range(20))
    text = (tmp_path / "out" / "r0.sce").read_text()
    assert f"keep(it == {rows[0]['v']!r}kph)" in text


def test_ranges_that_list_values_and_a_continuous_one_under_full(tmp_path):
    (tmp_path / "l.osc").write_text("import osc.helpers\nscenario l:\n    n: int = 1 with:\n        keep(it in [1..4])\n"
                                    "    v: speed = 10kph with:\n        keep(it in range(10kph, 30kph, 10kph))\n"
                                    "    do serial:\n        log(n)\n")
    done = vary(tmp_path, "l.osc", "--list")
    assert done.returncode == 0, done.stderr
    assert "12 variants would be generated" in done.stdout
    assert "l.v: 3 values [10kph, 20kph, 30kph]" in done.stdout
    (tmp_path / "r.osc").write_text(CONTINUOUS)
    refused = vary(tmp_path, "r.osc")
    assert refused.returncode == 1
    assert refused.stderr.startswith("r.osc:5:20: error: 'r.v' is a continuous range (10.0kph..30.0kph)")
    assert "--strategy lhs|random|sobol|halton" in refused.stderr


def test_samplers_need_a_sample_size(tmp_path):
    (tmp_path / "r.osc").write_text(CONTINUOUS)
    done = vary(tmp_path, "r.osc", "--strategy", "lhs")
    assert done.returncode == 1
    assert "--strategy lhs needs --samples N" in done.stderr


def test_a_value_that_does_not_resolve_stops_every_strategy_before_writing(tmp_path):
    (tmp_path / "b.osc").write_text(
        "import osc.helpers\nscenario b:\n    x: int = 0 with:\n        keep(it in [1, 2, 'three'])\n"
        "    y: int = 0 with:\n        keep(it in [1, 2])\n    z: int = 0 with:\n        keep(it in [1, 2])\n"
        "    do serial:\n        log(x)\n")
    done = vary(tmp_path, "b.osc", "--strategy", "pairwise", "--seed", "1")
    assert done.returncode == 1
    assert "b.x = 'three' does not resolve" in done.stderr and "nothing was written" in done.stderr
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").glob("*.sce"))
    assert "(4 impossible: they hold a value that does not resolve)" in done.stdout   # what the array would cover


def test_sobol_points_come_from_scipy(tmp_path):
    (tmp_path / "r.osc").write_text(CONTINUOUS)
    done = vary(tmp_path, "r.osc", "--strategy", "sobol", "--samples", "8", "--seed", "2")
    assert done.returncode == 0, done.stderr
    rows = assignments(tmp_path / "out")
    assert len(rows) == 8 and all(10 <= float(r["v"]) <= 30 for r in rows)
    # a scrambled Sobol set of 8 points puts one point in each eighth of each axis
    assert sorted(int((float(r["g"]) - 0.5) / 2 * 8) for r in rows) == list(range(8))


def test_foretify_unit_after_the_bracket_is_the_same_range(tmp_path):
    (tmp_path / "a.osc").write_text(CONTINUOUS)
    (tmp_path / "b.osc").write_text(CONTINUOUS.replace("[10kph..30kph]", "[10..30]kph"))
    for name in ("a", "b"):
        done = vary(tmp_path, f"{name}.osc", "--strategy", "lhs", "--samples", "5", "--seed", "8", "-o", name)
        assert done.returncode == 0, done.stderr
        assert "r.v: range [10.0kph..30.0kph]" in done.stdout
    assert assignments(tmp_path / "a") == assignments(tmp_path / "b")
    (tmp_path / "c.osc").write_text(CONTINUOUS.replace("[10kph..30kph]", "[10..x]kph"))
    refused = vary(tmp_path, "c.osc", "--strategy", "lhs", "--samples", "5")
    assert refused.returncode == 1 and "a range end must be a number" in refused.stderr


def test_drawn_numbers_in_exponent_form_read_back_the_same_everywhere(tmp_path):
    """A drawn number whose repr has an exponent (``5.3e-05``) is spelled the slow way in the YAML
    assignment (PyYAML's ``5.3e-05`` would read back as a string) but the same number everywhere."""
    (tmp_path / "tiny.osc").write_text("import osc.helpers\nscenario t:\n    d: float = 0.0 with:\n"
                                       "        keep(it in [0.0..0.0001])\n    w: float = 0.0 with:\n"
                                       "        keep(it in [1.0..2.0])\n    do serial:\n        log(d)\n")
    done = vary(tmp_path, "tiny.osc", "--strategy", "lhs", "--samples", "12", "--seed", "5")
    assert done.returncode == 0, done.stderr
    files = sorted((tmp_path / "out").glob("*.sce"))
    assert len(files) == 12
    exponents = 0
    for path in files:
        sce = read_sce(path)
        d, w = sce.assignment["t.d"], sce.assignment["t.w"]
        assert isinstance(d, float) and 0.0 <= d <= 0.0001 and isinstance(w, float) and 1.0 <= w <= 2.0
        text = path.read_text()
        assert f"keep(it == {d!r})" in text and f"keep(it == {w!r})" in text
        # the header comment shows the value rounded to 4 significant digits (the assignment keeps it exact)
        assert f"# t.d = {drawn_text(d)}\n" in text and f"# t.w = {drawn_text(w)}\n" in text
        exponents += "e-" in repr(d)
    assert exponents >= 10          # all but the top stratum (values of 1e-4 and up) print an exponent
