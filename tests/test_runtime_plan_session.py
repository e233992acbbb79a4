"""Run planning (names, output dirs), simulations (loading, reset injection, life cycle), JUnit output."""

from __future__ import annotations

import io
import os
import xml.etree.ElementTree as ET

import pytest
from runtime_models import log, parameter, scenario, serial, wait_elapsed

from coverage_engine.errors import ParameterFileError
from coverage_engine.resolve import model as m
from coverage_engine.results.run_report import ReportWriter, parse_error_result, write_grouped, write_results
from coverage_engine.results.scenario_result import ScenarioResult
from executor.runtime.logger import Logger
from executor.runtime.planned_runs import PlannedRun, plan_runs, split_output_dirs
from executor.runtime.session import SessionOptions, run_session
from executor.runtime.simulation import SimulationError, SimulationInterface, load_simulation, reset_arguments


def file_of(*scenarios) -> m.ScenarioFile:
    return m.ScenarioFile("x.osc", tuple(scenarios))


def test_single_scenario_single_document_writes_to_root(tmp_path):
    runs = plan_runs([(file_of(scenario(None, "a")), {})], str(tmp_path))
    assert [(r.name, r.output_dir) for r in runs] == [("a", str(tmp_path))]


def test_several_scenarios_and_documents(tmp_path):
    sf = file_of(scenario(None, "a"), scenario(None, "b"))
    runs = plan_runs([(sf, {}), (sf, {"b": "custom/place"})], str(tmp_path))
    assert [r.name for r in runs] == ["a-0", "b-0", "a-1", "b-1"]
    assert runs[0].output_dir == str(tmp_path / "a-0")
    assert runs[3].output_dir == str(tmp_path / "custom" / "place")


def test_absolute_output_dir_and_no_root(tmp_path):
    target = str(tmp_path / "abs")
    runs = plan_runs([(file_of(scenario(None, "a"), scenario(None, "b")), {"a": target})], None)
    assert [r.output_dir for r in runs] == [target, None]


def test_split_output_dirs_validates():
    overrides, dirs = split_output_dirs({"a": {"_output_dir": "x", "v": 1}, "b": {"w": 2}})
    assert overrides == {"a": {"v": 1}, "b": {"w": 2}} and dirs == {"a": "x"}
    for bad in (5, "", "../out", "sub/../../out"):
        with pytest.raises(ParameterFileError):
            split_output_dirs({"a": {"_output_dir": bad}})
    assert split_output_dirs(None) == (None, {})


class Sim(SimulationInterface):
    events: list = []

    @property
    def dt(self):
        return 0.01

    def setup(self, **kwargs):
        self.events.append("setup")

    def reset(self, speed, label="none"):
        self.events.append(("reset", speed, label))

    def step(self):
        pass

    def shutdown(self):
        self.events.append("shutdown")


def test_reset_arguments_by_name_and_missing_required():
    sim = Sim()
    assert reset_arguments(sim, {"speed": 2.0, "other": 1}) == {"speed": 2.0}
    with pytest.raises(SimulationError, match="'speed'"):
        reset_arguments(sim, {"label": "x"}, "no_speed")


def test_load_simulation_specs(tmp_path, monkeypatch):
    source = tmp_path / "my_sim_mod.py"
    source.write_text("class S:\n    dt = 0.5\n    def step(self):\n        pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert load_simulation("my_sim_mod:S").dt == 0.5
    assert load_simulation(f"{source}:S").dt == 0.5
    assert load_simulation(str(source)).dt == 0.5
    for bad in ("no_such_module_xyz:S", "my_sim_mod:Nope", "my_sim_mod", str(tmp_path / "missing.py")):
        with pytest.raises(SimulationError):
            load_simulation(bad)


def test_session_simulation_life_cycle_and_no_sleep(tmp_path):
    Sim.events = []
    runs = [PlannedRun(scenario(serial(wait_elapsed(50.0), log("x")), "a", parameters=[parameter("speed", 1.5)]),
                       "a", str(tmp_path / "a")),
            PlannedRun(scenario(log("y"), "b"), "b", str(tmp_path / "b")),
            PlannedRun(scenario(log("z"), "c", parameters=[parameter("speed", 3.0)]), "c", None)]
    out = io.StringIO()
    outcome = run_session(runs, SessionOptions(simulation=Sim()), Logger(stream=out))
    assert Sim.events == ["setup", ("reset", 1.5, "none"), ("reset", 3.0, "none"), "shutdown"]
    assert [r.passed for r in outcome.results] == [True, False, True]
    assert "'speed'" in outcome.results[1].message
    assert (tmp_path / "a").is_dir() and not outcome.passed


def test_junit_files(tmp_path):
    results = [ScenarioResult("ok", True, duration=0.5),
               ScenarioResult("bad", False, "emit fail", "tree <snapshot> & more", output_dir=str(tmp_path / "bad"))]
    path = write_results(tmp_path, results)
    suite = ET.parse(path).getroot().find("testsuite")
    assert suite.get("tests") == "2" and suite.get("failures") == "1"
    failure = suite.findall("testcase")[1].find("failure")
    assert failure.get("message") == "emit fail" and "<snapshot> & more" in failure.text
    written = write_grouped(results, str(tmp_path / "root"), per_scenario=True)
    assert sorted(os.path.relpath(p, tmp_path) for p in written) == ["bad/test.xml", "root/test.xml"]
    error = write_results(tmp_path / "err", [parse_error_result("x.osc", "syntax error")])
    assert ET.parse(error).getroot().find("testsuite").get("failures") == "1"


def test_report_writer_rewrites_only_the_reports_that_changed(tmp_path):
    writer = ReportWriter(str(tmp_path), per_scenario=True)
    first = ScenarioResult("a", True, start_time=1.0, output_dir=str(tmp_path / "a"))
    assert writer.update([first]) == [tmp_path / "a/test.xml"]
    second = ScenarioResult("b", False, "not run", output_dir=str(tmp_path / "b"), skipped=True)
    assert writer.update([first, second], final=True) == [tmp_path / "b/test.xml"]
    assert writer.update([first, second], final=True) == []
    case = ET.parse(tmp_path / "b/test.xml").getroot().find(".//testcase")
    assert case.find("skipped").get("message") == "not run" and case.get("timestamp") is None
    combined = ReportWriter(str(tmp_path / "all"), per_scenario=False)
    assert combined.update([first, second]) == [tmp_path / "all/test.xml"]
    suite = ET.parse(tmp_path / "all/test.xml").getroot().find("testsuite")
    assert suite.get("tests") == "2" and suite.get("skipped") == "1" and suite.get("failures") == "0"


def test_report_writer_waits_in_proportion_to_what_a_write_costs(tmp_path):
    """A report of k results costs k to write: rewriting it after each of n scenarios cost n² (issue 32
    item 8). The next write waits REWRITE_RATIO times the last write's duration; the final one never."""
    writer = ReportWriter(str(tmp_path), per_scenario=False)
    writer.REWRITE_RATIO = 1e9                       # (any write then makes the next one wait for ever)
    results = [ScenarioResult("a", True, start_time=1.0)]
    assert writer.update(results) == [tmp_path / "test.xml"]
    results.append(ScenarioResult("b", True, start_time=2.0))
    assert writer.update(results) == []
    assert writer.update(results, final=True) == [tmp_path / "test.xml"]
    assert ET.parse(tmp_path / "test.xml").getroot().find("testsuite").get("tests") == "2"
