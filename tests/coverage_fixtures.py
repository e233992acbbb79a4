"""Results folders made by the real commands, for the coverage tests (a pytest plugin).

``child_batch``: ``scenario_variation`` expands a cut-in (3 speeds x 2 gaps x 2 lanes = 12 variants),
``scenario_batch_execution`` runs each with a foreign child (``tests/coverage_child.py``: plain Python
writing ``test.xml`` and ``coverage.json`` by hand). ``execution_batch``: 6 variants run by our own
``scenario_execution`` (no coverage.json: input coverage only). Both are built once per session.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from coverage_support import BIN, run

HERE = Path(__file__).resolve().parent

CUT_IN = """\
import osc.helpers

enum side: [left, right]

scenario cut_in:
    speed: float = 10.0
    gap: int = 10
    lane: side = side!left
    keep(speed in [10.0, 20.0, 30.0])
    keep(gap in [5, 10])
    keep(lane in [side!left, side!right])
    do serial:
        log(speed)
        compare(gap, ">", 5)
"""

FOLLOW = """\
import osc.helpers

scenario follow:
    speed: float = 10.0
    gap: int = 10
    keep(speed in [10.0, 20.0, 30.0])
    keep(gap in [5, 10])
    do serial:
        log(speed)
        compare(gap, ">", 5)
"""


@dataclass(frozen=True)
class Batch:
    root: Path
    results: Path
    store: str


def _make(root: Path, text: str, name: str, command: list[str]) -> Batch:
    root.mkdir(parents=True, exist_ok=True)
    (root / f"{name}.osc").write_text(text, encoding="utf-8")
    store = f"sqlite:///{root / 'store.db'}"
    made = run(str(BIN / "scenario_variation"), f"{name}.osc", "-o", "out", "--store", store, cwd=root)
    assert made.returncode == 0, made.stdout + made.stderr
    ran = run(str(BIN / "scenario_batch_execution"), "-i", "out", "-o", "results", "-j", "2", "--store", store,
              "--", *command, cwd=root)
    assert (root / "results" / "test.xml").exists(), ran.stdout + ran.stderr
    return Batch(root=root, results=root / "results", store=store)


@pytest.fixture(scope="session")
def child_batch(tmp_path_factory) -> Batch:
    root = tmp_path_factory.mktemp("child_batch")
    return _make(root, CUT_IN, "cut_in",
                 [sys.executable, str(HERE / "coverage_child.py"), "{SCENARIO}", "{OUTPUT_DIR}"])


@pytest.fixture(scope="session")
def execution_batch(tmp_path_factory) -> Batch:
    root = tmp_path_factory.mktemp("execution_batch")
    return _make(root, FOLLOW, "follow",
                 [str(BIN / "scenario_execution"), "{SCENARIO}", "--output-dir", "{OUTPUT_DIR}"])
