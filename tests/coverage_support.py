"""Helpers of the coverage tests: run our commands as subprocesses."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

BIN = Path(sys.executable).parent


def run(*args: str, cwd: Path, timeout: float = 300, check: bool = True) -> subprocess.CompletedProcess:
    """Run one of our commands (or any program); stdout and stderr kept apart."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    done = subprocess.run(list(args), cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env)
    if check and done.returncode not in (0, 1):
        raise AssertionError(f"{' '.join(args)} exited {done.returncode}:\n{done.stdout}\n{done.stderr}")
    return done


def coverage(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return run(str(BIN / "scenario_coverage"), *args, cwd=cwd, check=False)
