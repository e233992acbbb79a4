"""Helpers for the real-engine tests (``test_sim_*.py``): the example package, runs, reading the results.

The engines are the ``sim`` extra, which ``.ci/run`` installs: without them these tests fail (they
are not skipped), as every test of a part the project ships must be able to fail.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
BIN = Path(sys.executable).parent
PYBULLET_SIM = "executor.simulations.pybullet:PyBulletSimulation"
BALL_SIM = f"{EXAMPLES / 'mujoco' / 'sim.py'}:BallSimulation"


def run(command: str, *args: str, cwd: Path, env: dict | None = None, timeout: float = 120) -> subprocess.CompletedProcess:
    """Run one of our commands from the test's virtualenv; stdout and stderr together in ``.stdout``."""
    full_env = dict(os.environ, PYTHONUNBUFFERED="1", NO_COLOR="1")
    full_env.update(env or {})
    return subprocess.run([str(BIN / command), *args], cwd=cwd, env=full_env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=timeout)


def execute(*args: str, cwd: Path, env: dict | None = None, timeout: float = 120) -> subprocess.CompletedProcess:
    return run("scenario_execution", *args, cwd=cwd, env=env, timeout=timeout)


def verdicts(report: Path) -> dict[str, str]:
    """``testcase name -> passed | failure | error`` of a JUnit file."""
    found = {}
    for case in ET.parse(report).getroot().iter("testcase"):
        outcome = "passed"
        for kind in ("failure", "error"):
            if case.find(kind) is not None:
                outcome = kind
        found[case.get("name")] = outcome
    return found


def logged_numbers(text: str, label: str) -> list[float]:
    """The numbers logged by ``log(...)`` actions named ``label`` (``[INFO] [label] 1.25``)."""
    return [float(v) for v in re.findall(rf"\[{re.escape(label)}\] (-?[0-9.e+-]+)\s*$", text, re.MULTILINE)]


def driven(text: str) -> list[tuple[float, float]]:
    """``(driven, straight line)`` metres of every finished navigation goal in a log."""
    return [(float(a), float(b)) for a, b in re.findall(r"driven ([0-9.]+) m \(straight line ([0-9.]+) m\)", text)]


def mujoco_drop_env(tmp_path: Path) -> dict[str, str]:
    """An environment in which the example package ``mujoco_drop`` is importable: as is (``.ci/run``
    installs it), else installed into ``tmp_path`` for the test's child processes. Fails when it cannot be."""
    if importlib.util.find_spec("mujoco_drop") is not None:
        return {}
    target = tmp_path / "site"
    errors = []
    for isolation in (["--no-build-isolation"], []):
        done = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", *isolation, "--target",
                               str(target), str(EXAMPLES / "mujoco")], capture_output=True, text=True, cwd=tmp_path)
        if done.returncode == 0:
            return {"PYTHONPATH": str(target)}
        errors.append(done.stderr.strip())
    pytest.fail("cannot install examples/mujoco (pip install -e examples/mujoco):\n" + "\n".join(errors))
