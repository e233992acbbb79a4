"""Variation examples over each engine, end to end: scenario_variation, then scenario_batch_execution.

The coverage report (scenario_coverage) and the built-in runner take over from the launched command
once they exist; until then the merged JUnit report's ``variation.*`` suite properties carry the
inputs of every variant and its verdict.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from sim_support import (
    BALL_SIM,
    EXAMPLES,
    PYBULLET_SIM,
    mujoco_drop_env,
    run,
)

# Each test expands a variation and runs a batch of its variants: several seconds each.
pytestmark = pytest.mark.slow


def variate_and_batch(source: Path, tmp_path: Path, simulation: str, keep: list[int] | None = None,
                      env: dict | None = None, builtin: bool = False) -> dict[str, tuple[str, dict[str, str]]]:
    """Expand ``source``, run the variants (only ``keep`` when given) with -j 2; name -> (status, variation)."""
    store = f"sqlite:///{tmp_path / 'store.db'}"
    made = run("scenario_variation", str(source), "-o", "in", "--store", store, cwd=tmp_path, env=env)
    assert made.returncode == 0, made.stdout
    if keep is not None:
        for variant in (tmp_path / "in").glob("*.sce"):
            if int(variant.stem.removeprefix(source.stem)) not in keep:
                variant.unlink()
    runner = ["--simulation", simulation] if builtin else [
        "--", "scenario_execution", "{SCENARIO}", "-o", "{OUTPUT_DIR}", "--simulation", simulation]
    ran = run("scenario_batch_execution", "-i", "in", "-o", "results", "-j", "2", "--store", store, *runner,
              cwd=tmp_path, env=env, timeout=600)
    outcome = {}
    for suite in ET.parse(tmp_path / "results" / "test.xml").getroot().iter("testsuite"):
        properties = {p.get("name"): p.get("value") for p in suite.iter("property")}
        variation = {k.split(".", 2)[-1]: v for k, v in properties.items() if k.startswith("variation.")}
        outcome[suite.get("name")] = (properties.get("status"), variation)
    assert ran.returncode == (0 if all(s == "passed" for s, _ in outcome.values()) else 1), ran.stdout
    return outcome


@pytest.mark.parametrize("builtin", [False, True], ids=["launched", "builtin"])
def test_pybullet_drive_variation(tmp_path, builtin):
    """The same verdicts whether each job is launched or forked by the built-in runner (--simulation)."""
    outcome = variate_and_batch(EXAMPLES / "pybullet" / "drive_variation_list.osc", tmp_path, PYBULLET_SIM,
                                keep=[0, 5, 10, 15], builtin=builtin)
    assert {name: status for name, (status, _) in outcome.items()} == {
        "drive_variation_list0": "failed",    # 2 rad/s, 0.1 N m: too slow for 2 m in 5 s
        "drive_variation_list5": "failed",    # 5 rad/s, 0.3 N m
        "drive_variation_list10": "passed",   # 8 rad/s, 1 N m
        "drive_variation_list15": "passed",   # 11 rad/s, 3 N m
    }
    assert outcome["drive_variation_list10"][1] == {"wheel_speed": "8mps", "motor_force": "1.0"}


def test_mujoco_drop_variation(tmp_path):
    env = mujoco_drop_env(tmp_path)
    outcome = variate_and_batch(EXAMPLES / "mujoco" / "drop_variation_list.osc", tmp_path, BALL_SIM,
                                keep=[0, 11, 12, 23], env=env)
    statuses = {name: status for name, (status, _) in outcome.items()}
    # free fall takes sqrt(2 h / g): 0.32 s from 0.5 m, 0.64 s from 2 m, 0.90 s from 4 m, 1.11 s from 6 m
    assert statuses == {"drop_variation_list0": "passed", "drop_variation_list11": "passed",
                        "drop_variation_list12": "passed", "drop_variation_list23": "failed"}


def test_fault_injection_sweep_reduced(tmp_path):
    source = EXAMPLES / "navigation" / "test_fault_injection.osc"
    outcome = variate_and_batch(source, tmp_path, PYBULLET_SIM, keep=[0, 7, 56, 58])
    statuses = {name: status for name, (status, _) in outcome.items()}
    assert statuses == {"test_fault_injection0": "passed",    # no noise, no drops
                        "test_fault_injection7": "passed",    # no noise, 70 % of the beams dropped
                        "test_fault_injection56": "failed",   # 0.7 m noise: phantom obstacles block the door
                        "test_fault_injection58": "failed"}   # 0.7 m noise, 20 % dropped
    assert outcome["test_fault_injection58"][1] == {"noise.parameter_value": "0.7",
                                                     "drop.parameter_value": "0.2"}
