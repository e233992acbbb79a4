"""Inputs at scale run in time linear in their size (issue 32 item 8).

A file of n scenarios cost n² twice over: the parser copied the growing list of declarations at each
one, and ``test.xml`` was rewritten in full after each scenario. 12,000 scenarios took far beyond the
timeout below (10,000 scenarios: over 300 s); now 6 to 22 s on 2 loaded cores.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import yaml
from coverage_support import BIN, run


def test_a_file_of_many_scenarios_runs_in_linear_time(tmp_path):
    count = 12_000
    lines = ["import osc.helpers"]
    for index in range(count):
        lines += [f"scenario s{index}:", "    do serial:", '        log("x")']
    (tmp_path / "many.osc").write_text("\n".join(lines) + "\n", encoding="utf-8")
    done = run(str(BIN / "scenario_execution"), "many.osc", "-o", "out", cwd=tmp_path, timeout=240)
    assert done.returncode == 0, done.stderr[-2000:]
    suite = ET.parse(tmp_path / "out" / "test.xml").getroot().find("testsuite")
    assert suite.get("tests") == str(count) and suite.get("failures") == "0"


def test_yaml_is_read_with_libyaml_where_pyyaml_has_it():
    from coverage_engine.yaml_bounds import SAFE_LOADER

    assert SAFE_LOADER is (yaml.CSafeLoader if yaml.__with_libyaml__ else yaml.SafeLoader)
