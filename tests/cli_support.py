"""Helpers for tests that run the real ``scenario_execution`` command as a subprocess."""

from __future__ import annotations

import functools
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

EXE = str(Path(sys.executable).parent / "scenario_execution")


@functools.lru_cache(maxsize=1)
def frontend_problem() -> str | None:
    """None when the parser and resolver can load a file importing osc.helpers, else the reason."""
    from coverage_engine.files.loader import load_scenario_file

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "probe.osc"
        path.write_text('import osc.helpers\nscenario probe:\n    do serial:\n        log("x")\n'
                        "        wait elapsed(1s)\n")
        try:
            load_scenario_file(path)
        except Exception as exc:  # noqa: BLE001 - any failure means "not ready yet"
            return f"{type(exc).__name__}: {exc}"
    return None


needs_frontend = pytest.mark.skipif(frontend_problem() is not None,
                                    reason=f"front end not ready: {frontend_problem()}")


def run_cli(*args: str, cwd: Path, timeout: float = 60, env: dict | None = None) -> subprocess.CompletedProcess:
    """Run scenario_execution; stdout and stderr together in ``.stdout``."""
    full_env = dict(os.environ, PYTHONUNBUFFERED="1", PYTHONPATH=str(cwd))
    full_env.update(env or {})
    return subprocess.run([EXE, *args], cwd=cwd, env=full_env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, timeout=timeout)
