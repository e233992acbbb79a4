"""Errors ``scenario_variation`` reports about the varied constraints themselves, at their positions.

Real command in a subprocess on real files.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from cli_support import run_variation

from coverage_engine.files.sce import read_sce


def run(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    return run_variation(tmp_path, *args)


@pytest.mark.parametrize("right, message", [
    ("[]", "empty value list"),
    ("[1.0..5.0]", "'test.log.msg' is a continuous range (1.0..5.0): --strategy full needs listed values"),
    ("'abc'", "the right side of 'in' must be a list of values"),
    ("[1..2.5kph]", "the ends of a range must be written in one unit"),
])
def test_an_in_that_is_no_dimension_is_an_error_at_its_position(tmp_path, right, message):
    (tmp_path / "e.osc").write_text("import osc.helpers\n\nscenario test:\n    do serial:\n        log() with:\n"
                                    f"            keep(it.msg in {right})\n")
    result = run(tmp_path, "e.osc")
    assert result.returncode == 1
    assert f"e.osc:6:28: error: {message}" in result.stderr
    assert "scenario_variation" not in result.stderr  # not "expand it ... with scenario_variation"
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "out").exists()


TWO_ON_ONE = """import osc.helpers
scenario test:
    do serial:
        log() with:
            keep(it.msg in ['a'])
            keep(it.msg in ['b', 'c'])
"""


def test_two_keeps_on_one_parameter_are_one_dimension_and_errors_point_at_the_value(tmp_path):
    (tmp_path / "two.osc").write_text(TWO_ON_ONE)
    result = run(tmp_path, "two.osc")
    assert "2 combinations (2)," in result.stdout  # one dimension, not "(1 x 2)"
    assert "test.log.msg#2: 2 values ['b', 'c'] (the same parameter as line 5" in result.stdout
    assert "two.osc:6:29: error: test.log.msg = 'a', test.log.msg#2 = 'b' does not resolve" in result.stderr
    assert "two.osc:6:34: error: test.log.msg = 'a', test.log.msg#2 = 'c' does not resolve" in result.stderr
    assert "two.osc:5:" not in result.stderr


def test_two_keeps_on_one_member_have_their_own_assignment_keys(tmp_path):
    (tmp_path / "m.osc").write_text("import osc.helpers\n\nscenario test:\n    x: int with:\n"
                                    "        keep(it in [1, 2])\n    keep(x in [1, 3])\n    do log('x')\n")
    result = run(tmp_path, "m.osc")
    assert "4 combinations (4)," in result.stdout
    sce = (tmp_path / "out" / "m1.sce").read_text()
    assert '  "test.x": 1\n  "test.x#2": 3\n' in sce  # a YAML key appears once
    assert read_sce(tmp_path / "out" / "m1.sce").assignment == {"test.x": 1, "test.x#2": 3}
