"""``scenario_variation --only-new`` (issue 12, item 5): add to earlier runs instead of starting over."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest
import yaml
from cli_support import SAMPLED_DRIVE as SAMPLED
from cli_support import run_variation

GRID = """import osc.helpers

scenario grid:
    a: int with:
        keep(it in [1, 2, 3])
    b: int with:
        keep(it in [1, 2, 3])
    c: int with:
        keep(it in [1, 2, 3])
    d: int with:
        keep(it in [1, 2, 3])
    do serial:
        log("x")
"""


def vary(cwd: Path, *args: str):
    done = run_variation(cwd, *args, "--store", f"sqlite:///{cwd}/store.db")
    assert done.returncode == 0, done.stdout + done.stderr
    return done


def variants(folder: Path) -> dict[str, dict]:
    return {p.name: yaml.safe_load(p.read_text()) for p in folder.glob("*.sce")}


def key(sce: dict) -> str:
    return repr(sorted(sce["assignment"].items()))


@pytest.mark.parametrize("strategy", ["random", "sobol", "halton"])
def test_a_sampler_continues_its_sequence_and_writes_only_the_new_variants(tmp_path, strategy):
    (tmp_path / "drive.osc").write_text(SAMPLED)
    vary(tmp_path, "drive.osc", "--strategy", strategy, "--samples", "5", "--seed", "11")
    before = {p.name: p.read_bytes() for p in (tmp_path / "out").glob("*.sce")}
    done = vary(tmp_path, "drive.osc", "--strategy", strategy, "--samples", "8", "--seed", "11", "--only-new")
    assert "wrote 3 new scenario file(s) to out/; 5 variant(s) earlier runs wrote were not written again" \
        in done.stdout
    after = variants(tmp_path / "out")
    assert sorted(after) == sorted(f"drive{i}.sce" for i in range(8))
    assert all((tmp_path / "out" / name).read_bytes() == data for name, data in before.items())
    vary(tmp_path, "drive.osc", "--strategy", strategy, "--samples", "8", "--seed", "11", "-o", "fresh")
    assert {key(v) for v in after.values()} == {key(v) for v in variants(tmp_path / "fresh").values()}


def test_lhs_refuses_to_add_to_an_earlier_design_and_says_why(tmp_path):
    (tmp_path / "drive.osc").write_text(SAMPLED)
    vary(tmp_path, "drive.osc", "--strategy", "lhs", "--samples", "20", "--seed", "7")
    before = {p.name: p.read_bytes() for p in (tmp_path / "out").glob("*.sce")}
    refused = run_variation(tmp_path, "drive.osc", "--strategy", "lhs", "--samples", "50", "--seed", "7", "--only-new",
                            "--store", f"sqlite:///{tmp_path}/store.db")
    assert refused.returncode == 1
    assert refused.stderr.startswith("drive.osc: error: --strategy lhs --samples 50 --only-new cannot add to the 20 "
                                     "variant(s) earlier runs wrote (--strategy lhs, --samples 20): a Latin hypercube "
                                     "of 50 points has one point in each 1/50 of every range")
    assert "hint: grow a sample run by run with --strategy sobol, halton or random" in refused.stderr
    assert "Traceback" not in refused.stderr
    assert {p.name: p.read_bytes() for p in (tmp_path / "out").glob("*.sce")} == before
    again = vary(tmp_path, "drive.osc", "--strategy", "lhs", "--samples", "20", "--seed", "7", "--only-new")
    assert "wrote 0 new scenario file(s)" in again.stdout


def test_prefix_stable_samplers_continue_their_sequence(tmp_path):
    (tmp_path / "drive.osc").write_text(SAMPLED)
    vary(tmp_path, "drive.osc", "--strategy", "halton", "--samples", "10", "--seed", "3", "-o", "inc")
    vary(tmp_path, "drive.osc", "--strategy", "halton", "--samples", "25", "--seed", "3", "-o", "inc", "--only-new")
    vary(tmp_path, "drive.osc", "--strategy", "halton", "--samples", "25", "--seed", "3", "-o", "fresh")
    incremental = {key(v) for v in variants(tmp_path / "inc").values()}
    fresh = {key(v) for v in variants(tmp_path / "fresh").values()}
    assert incremental == fresh and len(fresh) == 25


def triples(rows: list[tuple[int, ...]]) -> set:
    return {(axes, tuple(r[a] for a in axes)) for r in rows for axes in itertools.combinations(range(4), 3)}


def test_t_way_after_pairwise_adds_only_the_rows_the_triples_need(tmp_path):
    (tmp_path / "grid.osc").write_text(GRID)
    vary(tmp_path, "grid.osc", "--strategy", "pairwise", "--seed", "1")
    earlier = [tuple(v["assignment"][f"grid.{k}"] for k in "abcd") for v in variants(tmp_path / "out").values()]
    done = vary(tmp_path, "grid.osc", "--strategy", "t-way", "--strength", "3", "--seed", "1", "--only-new")
    rows = [tuple(v["assignment"][f"grid.{k}"] for k in "abcd") for v in variants(tmp_path / "out").values()]
    assert len(set(rows)) == len(rows)
    every = set(itertools.product([1, 2, 3], repeat=4))
    assert triples(rows) == triples(sorted(every)), "a triple is not covered by the pairwise rows plus the new ones"
    added = [r for r in rows if r not in earlier]
    assert len(added) == len(rows) - len(earlier) > 0
    # every new row is needed: it holds a triple the pairwise rows do not
    assert all(triples([r]) - triples(earlier) for r in added)
    assert len(added) < len(every) - len(earlier)
    assert f"wrote {len(added)} new scenario file(s)" in done.stdout


def test_the_full_product_again_writes_nothing_new(tmp_path):
    (tmp_path / "grid.osc").write_text(GRID)
    vary(tmp_path, "grid.osc")
    done = vary(tmp_path, "grid.osc", "--only-new")
    assert "wrote 0 new scenario file(s) to out/; 81 variant(s) earlier runs wrote were not written again" \
        in done.stdout
    assert len(list((tmp_path / "out").glob("*.sce"))) == 81
