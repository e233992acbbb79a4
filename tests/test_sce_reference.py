"""A ``.sce`` written by the reference coverage package's ``scenario_variation`` (issue 33, item 5).

The reference dumps its model tree as YAML: ``#<path>==<value>`` comment lines naming what was varied,
then a list of single-key mappings, one per declaration. Each of our three readers (``scenario_execution``,
the batch, the pytest plugin) says in one located line where the file came from and what to do, instead of
"not a .sce file". The file below is a small one of ours in the same form.
"""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from batch_fixtures import cli_env, run_cli
from cli_support import run_cli as execute

REFERENCE_SCE = """#CompilationUnit.test_log.ScenarioDeclaration.ParameterDeclaration.msg=="bar"
- PhysicalTypeDeclaration:
    name: time
    _children:
    - SIBaseExponent:
        unit: s
        value: 1
- ScenarioDeclaration:
    qualified_behavior_name: test_log
    _children:
    - ParameterDeclaration:
        field_name:
        - msg
        _children: []
"""

OURS = 'import osc.helpers\nscenario fine:\n    do serial:\n        log("fine")\n'

MESSAGE = ("log1.sce:2:1: error: written by the reference's scenario_variation (a YAML dump of its model tree), "
           "which this tool does not run: regenerate the variants from the .osc with our scenario_variation, "
           "which reads the same 'keep(... in [...])'")


def inputs(tmp_path: Path) -> Path:
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "log1.sce").write_text(REFERENCE_SCE, encoding="utf-8")
    (folder / "fine.osc").write_text(OURS, encoding="utf-8")
    return folder


def test_scenario_execution_says_where_the_file_came_from_in_one_located_line(tmp_path):
    folder = inputs(tmp_path)
    done = execute(str(folder / "log1.sce"), "-o", "out", cwd=tmp_path)
    assert done.returncode == 1
    assert done.stdout.strip() == f"{folder}/{MESSAGE}"
    assert "not a .sce file" not in done.stdout


def test_the_batch_reports_one_testcase_per_reference_file_and_runs_the_others(tmp_path):
    inputs(tmp_path)
    done = run_cli(["-i", "in", "-o", "res"], tmp_path, cli_env(tmp_path))
    assert done.returncode == 1, done.stdout + done.stderr
    assert MESSAGE in done.stdout
    cases = {case.get("classname").split(".")[0]: case for case in ET.parse(tmp_path / "res/test.xml").iter("testcase")}
    assert sorted(cases) == ["fine", "log1"]
    assert len(cases["fine"]) == 0                                    # passed
    problem = cases["log1"].find("failure")
    assert problem is not None and problem.get("message", "").startswith(
        f"{tmp_path / 'in' / 'log1.sce'}:2:1: error: written by the reference's scenario_variation")   # located


def test_the_pytest_plugin_fails_the_item_with_the_same_line(tmp_path):
    inputs(tmp_path)
    env = dict(os.environ)
    env.pop("PYTEST_ADDOPTS", None)
    done = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:randomly", "-p", "no:cacheprovider", "--osc",
                           "in", "-q"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=180)
    assert done.returncode == 1, done.stdout + done.stderr
    assert "1 failed, 1 passed" in done.stdout
    assert MESSAGE in done.stdout
