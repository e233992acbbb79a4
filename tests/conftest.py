"""Shared test set-up: the project's console scripts are on PATH for subprocess-based tests."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent

# Tests run the real commands as subprocesses; make the ones installed beside this interpreter win.
os.environ["PATH"] = f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"
os.environ.setdefault("NO_COLOR", "1")


@pytest.fixture
def project_root() -> Path:
    """The repository root (examples/, benchmarks/ live there)."""
    return ROOT


@pytest.fixture(autouse=True)
def _end_background_runners():
    """A runner a test started in the background never outlives the test, even when the test fails."""
    yield
    from batch_fixtures import end_started
    end_started()
