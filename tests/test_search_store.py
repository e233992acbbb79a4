"""``scenario_variation --from RESULTS --store URL``: an adaptive round reads the earlier runs from the batch
store (a real SQLite file and the real PostgreSQL), through the real CLIs in a pipe, and proposes exactly
what it proposes from the results folders — even once the folders are gone from this host.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from batch_fixtures import cli_env, run_cli
from cli_support import run_variation
from test_search_strategies import assignments, braking

from coverage_engine.proposals import SEARCH_FILE

pytestmark = pytest.mark.slow
pytest_plugins = ["batch_stores"]


def vary(cwd: Path, *args: str) -> str:
    done = run_variation(cwd, "brake.osc", *args)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def batch(cwd: Path, url: str, variants: str, results: str) -> None:
    done = run_cli(["-i", variants, "-o", results, "--store", url], cwd, cli_env(cwd))
    assert done.returncode in (0, 1), done.stdout + done.stderr     # 1: some variant failed, as expected


def estimate(folder: Path) -> dict:
    search = json.loads((folder / SEARCH_FILE).read_text())
    return {key: search[key] for key in ("round", "strategy", "from", "runs_read", "objective", "estimate")}


def test_a_round_proposes_from_the_store_as_from_the_folders(tmp_path, store_url):
    (tmp_path / "brake.osc").write_text(braking(80.0))
    vary(tmp_path, "--strategy", "lhs", "--samples", "12", "--seed", "5", "--store", store_url, "-o", "round1")
    batch(tmp_path, store_url, "round1", "results1")
    boundary = ("--strategy", "boundary", "--samples", "6", "--seed", "2")
    falsify = ("--strategy", "falsify", "--objective", "min_gap", "--samples", "4", "--seed", "3")
    vary(tmp_path, "--from", "results1", *boundary, "-o", "folder_boundary")
    vary(tmp_path, "--from", "results1", *falsify, "-o", "folder_falsify")
    shutil.rmtree(tmp_path / "results1")           # from here on only the store knows the runs
    out = vary(tmp_path, "--from", "results1", "--store", store_url, *boundary, "-o", "round2")
    assert "round 2, strategy boundary: 12 earlier run(s) read" in out
    assert assignments(tmp_path / "round2") == assignments(tmp_path / "folder_boundary")
    assert estimate(tmp_path / "round2") == estimate(tmp_path / "folder_boundary")
    assert estimate(tmp_path / "round2")["estimate"]["boundary"]["pairs"] > 0     # verdicts of both sides read
    vary(tmp_path, "--from", "results1", "--store", store_url, *falsify, "-o", "store_falsify")
    worst = estimate(tmp_path / "store_falsify")["estimate"]["worst"]      # the record() values, from the store
    assert worst == estimate(tmp_path / "folder_falsify")["estimate"]["worst"] and worst["objective"] == "min_gap"
    assert assignments(tmp_path / "store_falsify") == assignments(tmp_path / "folder_falsify")
    # the next round reads its number from the store's copy of the round-2 variants' proposal line
    batch(tmp_path, store_url, "round2", "results2")
    shutil.rmtree(tmp_path / "round2")
    shutil.rmtree(tmp_path / "results2")
    out = vary(tmp_path, "--from", "results1", "--from", "results2", "--store", store_url, *boundary, "-o", "round3")
    assert "round 3, strategy boundary: 18 earlier run(s) read" in out
    assert estimate(tmp_path / "round3")["from"] == ["results1", "results2"]


def test_a_folder_the_store_holds_no_batch_of_is_a_located_error(tmp_path, store_url):
    (tmp_path / "brake.osc").write_text(braking(80.0))
    vary(tmp_path, "--strategy", "lhs", "--samples", "3", "--seed", "1", "--store", store_url, "-o", "round1")
    batch(tmp_path, store_url, "round1", "results1")
    done = run_variation(tmp_path, "brake.osc", "--from", "elsewhere", "--store", store_url, "--strategy", "boundary",
                         "--samples", "2", "-o", "round2")
    assert done.returncode == 1, done.stdout + done.stderr
    assert "holds no batch with output folder" in done.stderr and str(tmp_path / "elsewhere") in done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "round2").exists()
