"""Helpers for tests that run the real ``scenario_execution`` command as a subprocess."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXE = str(Path(sys.executable).parent / "scenario_execution")
EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

#: A scenario with a sampled range and a listed value: what the samplers and ``--only-new`` are tried on.
SAMPLED_DRIVE = """import osc.helpers

scenario drive:
    speed: speed with:
        keep(it in [10kph..90kph])
    lane: int with:
        keep(it in [1, 2, 3])
    do serial:
        log("x")
"""


def run_cli(*args: str, cwd: Path, timeout: float = 60, env: dict | None = None) -> subprocess.CompletedProcess:
    """Run scenario_execution; stdout and stderr together in ``.stdout``."""
    full_env = dict(os.environ, PYTHONUNBUFFERED="1", PYTHONPATH=str(cwd))
    full_env.update(env or {})
    return subprocess.run([EXE, *args], cwd=cwd, env=full_env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, timeout=timeout)


def example_library_env(target: Path) -> dict[str, str]:
    """Environment in which ``examples/example_library`` is installed: as is (``.ci/run`` installs it),
    else installed into ``target`` for the test's child processes. Fails when it cannot be installed."""
    import importlib.util

    if importlib.util.find_spec("example_library") is not None:
        return {}
    errors = []
    for isolation in (["--no-build-isolation"], []):
        install = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", *isolation,
                                  "--target", str(target), str(EXAMPLES / "example_library")],
                                 capture_output=True, text=True)
        if install.returncode == 0:
            return {"PYTHONPATH": str(target)}
        errors.append(install.stderr.strip())
    pytest.fail("cannot install examples/example_library (pip install ./examples/example_library):\n"
                + "\n".join(errors))


def run_variation(cwd: Path, *args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """Run the real ``scenario_variation`` in ``cwd`` with plain output and the default store of ``cwd``."""
    env = dict(os.environ, PYTHONPATH=str(EXAMPLES.parent), NO_COLOR="1")
    env.pop("SCENARIO_STORE", None)
    return subprocess.run([sys.executable, "-m", "cli.scenario_variation", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)
