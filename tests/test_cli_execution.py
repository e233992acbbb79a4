"""The real ``scenario_execution`` command, run as a subprocess on small scenario files."""

from __future__ import annotations

import signal
import subprocess
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from cli_support import EXE, run_cli

HELPERS = "import osc.helpers\n"


def write(tmp: Path, name: str, text: str) -> Path:
    path = tmp / name
    path.write_text(text)
    return path


def junit(path: Path) -> tuple[ET.Element, list[str]]:
    suite = ET.parse(path).getroot().find("testsuite")
    return suite, [case.get("name") for case in suite.iter("testcase")]


def test_help_lists_every_option(tmp_path):
    done = run_cli("-h", cwd=tmp_path)
    assert done.returncode == 0
    for option in ("--debug", "--log-model", "--live-tree", "--output-dir", "--dry-run", "--dot", "--step-duration",
                   "--scenario-parameter-file", "--create-scenario-parameter-file-template", "--post-run",
                   "--simulation", "--output-result-per-scenario"):
        assert option in done.stdout


@pytest.mark.parametrize("args", [[], ["--no-such-option", "x.osc"], ["x.txt"], ["missing.osc"],
                                  ["x.osc", "-s", "0"]])
def test_usage_errors_are_one_clear_message(tmp_path, args):
    (tmp_path / "x.txt").write_text("scenario a:\n    do log('x')\n")
    (tmp_path / "x.osc").write_text(HELPERS + "scenario a:\n    do log('x')\n")
    done = run_cli(*args, cwd=tmp_path)
    assert done.returncode != 0
    assert "Traceback" not in done.stdout and "error" in done.stdout.lower()


def test_missing_file_with_output_dir_writes_failing_test_xml(tmp_path):
    done = run_cli("UNKNOWN.osc", "-o", "deep/out", cwd=tmp_path)
    assert done.returncode != 0 and "Traceback" not in done.stdout
    suite, names = junit(tmp_path / "deep/out/test.xml")
    assert suite.get("failures") == "1" and suite.get("name") == "UNKNOWN" and names == ["UNKNOWN"]
    assert "UNKNOWN.osc" in suite.find("testcase/failure").get("message")


def test_run_writes_results_and_exit_code(tmp_path):
    write(tmp_path, "ok.osc", HELPERS + "scenario ok:\n    do serial:\n        log('hi there')\n        emit end\n")
    write(tmp_path, "bad.osc", HELPERS + "scenario bad:\n    do serial:\n        log('x')\n        emit fail\n")
    done = run_cli("ok.osc", "-o", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert "hi there" in done.stdout
    assert junit(tmp_path / "out/test.xml")[1] == ["ok"]
    done = run_cli("bad.osc", "-o", "out", cwd=tmp_path)
    assert done.returncode == 1
    suite, names = junit(tmp_path / "out/test.xml")
    assert names == ["bad"] and suite.get("failures") == "1"
    assert "emit fail" in ET.parse(tmp_path / "out/test.xml").getroot().find(".//failure").text


def test_action_without_implementation_is_an_error_even_in_dry_run(tmp_path):
    write(tmp_path, "s.osc", HELPERS + "action no_plugin_here:\n    p: string = 'x'\n"
                                       "scenario s:\n    do no_plugin_here()\n")
    done = run_cli("s.osc", "-n", cwd=tmp_path)
    assert done.returncode == 1 and "Traceback" not in done.stdout
    assert "no_plugin_here" in done.stdout and "scenario_execution.actions" in done.stdout
    assert done.stdout.startswith("s.osc:")


def test_dry_run_and_log_model_execute_nothing(tmp_path):
    write(tmp_path, "s.osc", HELPERS + "scenario s:\n    do log('executed')\n")
    done = run_cli("s.osc", "-n", "-l", "-o", "out", cwd=tmp_path)
    assert done.returncode == 0 and "executed" in done.stdout  # the model mentions it …
    assert "[INFO]" not in done.stdout and not (tmp_path / "out/test.xml").exists()  # … nothing ran


def test_multi_scenarios_documents_and_output_dirs(tmp_path):
    write(tmp_path, "two.osc", HELPERS + "scenario a:\n    v: string = 'a-default'\n    do log(v)\n"
                                         "scenario b:\n    w: string = 'b-default'\n    do log(w)\n")
    write(tmp_path, "p.yaml", "a:\n  v: a-doc0\n---\na:\n  v: a-doc1\n  _output_dir: custom\n")
    done = run_cli("two.osc", "--scenario-parameter-file", "p.yaml", "-o", "out", "--output-result-per-scenario",
                   cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert done.stdout.index("a-doc0") < done.stdout.index("b-default") < done.stdout.index("a-doc1")
    assert junit(tmp_path / "out/custom/test.xml")[1] == ["a-1"]
    assert junit(tmp_path / "out/b-1/test.xml")[1] == ["b-1"]
    assert not (tmp_path / "out/test.xml").exists()
    write(tmp_path, "escape.yaml", "a:\n  _output_dir: ../outside\n")
    done = run_cli("two.osc", "--scenario-parameter-file", "escape.yaml", "-o", "out2", cwd=tmp_path)
    assert done.returncode == 1 and "a-default" not in done.stdout and "Traceback" not in done.stdout


def test_post_run_hooks_in_order_after_test_xml(tmp_path):
    write(tmp_path, "s.osc", HELPERS + "scenario s:\n    do log('x')\n")
    hook = write(tmp_path, "hook.sh", '#!/bin/sh\necho "$0 $1 $(test -f "$1/test.xml" && echo xml)" >> calls.txt\n'
                                      "exit 3\n")
    hook.chmod(0o755)
    done = run_cli("s.osc", "-o", "out", "--post-run", "./hook.sh", "--post-run", "sh ./hook.sh", cwd=tmp_path)
    lines = (tmp_path / "calls.txt").read_text().splitlines()
    assert lines == [f"./hook.sh {tmp_path / 'out'} xml", f"./hook.sh {tmp_path / 'out'} xml"]
    assert "exit code 3" in done.stdout


def test_sigterm_records_aborted_and_ends_children(tmp_path):
    write(tmp_path, "long.osc", HELPERS + "scenario long:\n    do serial:\n        log('started')\n"
                                          "        run_process('sleep 61.25')\n")
    with subprocess.Popen([EXE, "long.osc", "-o", "out"], cwd=tmp_path, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True) as process:
        for line in process.stdout:
            if "started" in line:
                break
        time.sleep(0.5)  # the process starts on the next tick
        assert subprocess.run(["pgrep", "-f", "sleep 61.25"], capture_output=True).returncode == 0
        process.send_signal(signal.SIGTERM)
        output = process.stdout.read()
        process.wait(timeout=20)
    assert process.returncode == 128 + signal.SIGTERM, output
    assert subprocess.run(["pgrep", "-f", "sleep 61.25"], capture_output=True).returncode != 0
    root = ET.parse(tmp_path / "out/test.xml").getroot()
    assert [c.get("name") for c in root.iter("testcase")] == ["long"]
    message = root.find(".//failure").get("message")
    assert message.startswith("aborted by SIGTERM while 'run_process' at long.osc:5:9") and "long.osc:5:9" in message


# -- results survive a kill; an abort lists what never ran ------------------------------------------

THREE = HELPERS + ("scenario a:\n    do log('a done')\n"
                   "scenario b:\n    do serial:\n        log('b started')\n        wait elapsed(30s)\n"
                   "scenario c:\n    do log('c done')\n")


def start_until(tmp_path: Path, marker: str, *args: str) -> subprocess.Popen:
    """Start scenario_execution and return once ``marker`` is on its output."""
    process = subprocess.Popen([EXE, *args], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True)
    for line in process.stdout:
        if marker in line:
            return process
    process.wait(timeout=20)
    process.stdout.close()
    raise AssertionError(f"'{marker}' never printed (exit code {process.returncode})")


def test_kill_9_keeps_the_results_of_finished_scenarios(tmp_path):
    write(tmp_path, "abc.osc", THREE)
    with start_until(tmp_path, "b started", "abc.osc", "-o", "out") as process:
        process.kill()
        process.wait(timeout=20)
    suite, names = junit(tmp_path / "out/test.xml")
    assert names == ["a"] and suite.get("failures") == "0"
    assert not list((tmp_path / "out").glob(".test.xml.*"))  # no half-written report left behind


def test_ctrl_c_records_scenarios_that_never_started_as_skipped(tmp_path):
    write(tmp_path, "abc.osc", THREE)
    with start_until(tmp_path, "b started", "abc.osc", "-o", "out") as process:
        time.sleep(0.5)              # the tick that printed the marker moves on to the wait
        process.send_signal(signal.SIGINT)
        output = process.stdout.read()
        process.wait(timeout=20)
    assert process.returncode == 128 + signal.SIGINT, output
    suite, names = junit(tmp_path / "out/test.xml")
    assert names == ["a", "b", "c"]
    assert suite.get("failures") == "1" and suite.get("skipped") == "1"
    cases = {case.get("name"): case for case in suite.iter("testcase")}
    assert cases["b"].find("failure").get("message").startswith("aborted by SIGINT while 'wait' at abc.osc:7:9 ran")
    assert cases["c"].find("skipped").get("message").startswith("not run")
    assert "c done" not in output


def test_junit_timestamps_are_iso_8601(tmp_path):
    import datetime
    import re

    write(tmp_path, "ok.osc", HELPERS + "scenario ok:\n    do log('x')\n")
    before = datetime.datetime.now().replace(microsecond=0)
    done = run_cli("ok.osc", "-o", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    stamp = ET.parse(tmp_path / "out/test.xml").getroot().find("testsuite").get("timestamp")
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d", stamp), stamp
    assert abs((datetime.datetime.fromisoformat(stamp) - before).total_seconds()) < 60


# -- option values -----------------------------------------------------------------------------------

@pytest.mark.parametrize("value", ["inf", "-inf", "nan", "0", "-1", "1e400", "1e300", "fast"])
def test_step_duration_must_be_a_positive_finite_number(tmp_path, value):
    write(tmp_path, "s.osc", HELPERS + "scenario s:\n    do log('ran')\n")
    done = run_cli("s.osc", "-s", value, cwd=tmp_path)
    assert done.returncode == 2, done.stdout
    assert "--step-duration" in done.stdout and "Traceback" not in done.stdout and "ran" not in done.stdout


SIMULATIONS = """\
class Sim:
    def __init__(self):
        self.dt = DT
    def step(self):
        pass


class Boom:
    dt = 0.1
    def step(self):
        raise RuntimeError("step exploded")
"""


@pytest.mark.parametrize("dt", ["0", "-0.5", "float('nan')", "float('inf')", "'fast'"])
def test_simulation_dt_must_be_positive_and_finite(tmp_path, dt):
    write(tmp_path, "s.osc", HELPERS + "scenario s:\n    do log('ran')\n")
    write(tmp_path, "sims.py", f"DT = {dt}\n" + SIMULATIONS)
    done = run_cli("s.osc", "--simulation", "sims.py:Sim", "-o", "out", cwd=tmp_path)
    assert done.returncode == 1, done.stdout
    assert "internal error" not in done.stdout and "Traceback" not in done.stdout
    assert "dt must be a positive, finite number" in done.stdout and "Sim" in done.stdout
    assert done.stdout.count("error") == 1 and "ran" not in done.stdout
    suite, names = junit(tmp_path / "out/test.xml")
    assert names == ["s"] and suite.get("failures") == "1"


def test_simulation_step_failure_names_the_step_and_class(tmp_path):
    write(tmp_path, "s.osc", HELPERS + "scenario s:\n    do wait elapsed(1s)\n")
    write(tmp_path, "sims.py", "DT = 0.1\n" + SIMULATIONS)
    done = run_cli("s.osc", "--simulation", "sims.py:Boom", "-o", "out", cwd=tmp_path)
    assert done.returncode == 1 and "Traceback" not in done.stdout
    message = ET.parse(tmp_path / "out/test.xml").getroot().find(".//failure").get("message")
    assert message == "simulation step (Boom.step()) raised RuntimeError: step exploded"


# -- plugin actions that raise -----------------------------------------------------------------------

PLUGINS = """\
from executor.actions import ActionBase


class RaiseUpdate(ActionBase):
    def update(self):
        raise RuntimeError("update exploded")


class RaiseExecute(ActionBase):
    def execute(self, value):
        raise RuntimeError(f"execute exploded on {value}")


class RaiseSetup(ActionBase):
    def setup(self, **kwargs):
        raise RuntimeError("setup exploded")


class RaiseShutdown(ActionBase):
    def shutdown(self):
        raise RuntimeError("shutdown exploded")
"""


def install_plugins(tmp_path: Path) -> None:
    """A real distribution on PYTHONPATH (run_cli puts the cwd there) whose entry points name the actions."""
    write(tmp_path, "raising_actions.py", PLUGINS)
    info = tmp_path / "raising_actions-0.1.dist-info"
    info.mkdir()
    write(info, "METADATA", "Metadata-Version: 2.1\nName: raising-actions\nVersion: 0.1\n")
    write(info, "entry_points.txt", "[scenario_execution.actions]\n" + "".join(
        f"{name} = raising_actions:{cls}\n" for name, cls in
        (("raise_update", "RaiseUpdate"), ("raise_execute", "RaiseExecute"), ("raise_setup", "RaiseSetup"),
         ("raise_shutdown", "RaiseShutdown"))))


@pytest.mark.parametrize("action, expected", [
    ("raise_update()", "t.osc:8:9: error: action 'raise_update': update() raised RuntimeError: update exploded"),
    ("raise_execute(3)", "t.osc:8:9: error: action 'raise_execute': execute() raised RuntimeError: "
                         "execute exploded on 3"),
    ("raise_setup()", "setup failed: t.osc:8:9: error: action 'raise_setup': setup() raised RuntimeError: "
                      "setup exploded"),
])
def test_plugin_failures_name_the_action_and_its_position(tmp_path, action, expected):
    install_plugins(tmp_path)
    write(tmp_path, "t.osc", HELPERS + "action raise_update\naction raise_setup\naction raise_execute:\n"
                                       "    value: int\nscenario s:\n    do serial:\n        " + action + "\n")
    done = run_cli("t.osc", "-o", "out", cwd=tmp_path)
    assert done.returncode == 1 and "Traceback" not in done.stdout
    assert f"Scenario 's' failed: {expected}" in done.stdout
    assert ET.parse(tmp_path / "out/test.xml").getroot().find(".//failure").get("message") == expected


def test_plugin_shutdown_failure_names_the_action_and_its_position(tmp_path):
    install_plugins(tmp_path)
    write(tmp_path, "t.osc", HELPERS + "action raise_shutdown\nscenario s:\n    do serial:\n        log('x')\n"
                                       "        raise_shutdown()\n")
    done = run_cli("t.osc", cwd=tmp_path)
    assert "t.osc:6:9: error: action 'raise_shutdown': shutdown() raised RuntimeError: shutdown exploded" \
        in done.stdout, done.stdout


# -- parameter files -----------------------------------------------------------------------------------

PARAMETERISED = HELPERS + "scenario x:\n    speed: float = 1.0\n    label: string = 'label is 1'\n    do log(label)\n"


@pytest.mark.parametrize("text, expected", [
    ("x:\n  speed: 2.0\n---\nx:\n  nosuch: 1\n", "p.yaml:5:3: error: scenario 'x' has no parameter 'nosuch'"),
    ("nosuch: 1\n", "p.yaml:1:1: error: parameter file names unknown scenario 'nosuch'"),
    ("x:\n  speed: fast\n", "p.yaml:2:3: error: parameter 'x.speed'"),
    ("x:\n  _output_dir: 5\n", "p.yaml:2:3: error: 'x._output_dir'"),
    ("x:\n  speed: 2.0\n  speed: 3.0\n", "p.yaml:3:3: error: duplicate key 'speed' (first at line 2)"),
    ("x: {}\nx: {}\n", "p.yaml:2:1: error: duplicate key 'x'"),
])
def test_parameter_file_errors_name_the_file_and_key(tmp_path, text, expected):
    write(tmp_path, "x.osc", PARAMETERISED)
    write(tmp_path, "p.yaml", text)
    done = run_cli("x.osc", "--scenario-parameter-file", "p.yaml", "-o", "out", cwd=tmp_path)
    assert done.returncode == 1 and "Traceback" not in done.stdout
    assert done.stdout.startswith(expected), done.stdout
    assert "label is" not in done.stdout
    assert expected in ET.parse(tmp_path / "out/test.xml").getroot().find(".//failure").text


def test_empty_parameter_documents_add_no_run(tmp_path):
    """Issue 10 item 8: a leading, trailing or middle '---' with nothing in it is not a run."""
    write(tmp_path, "x.osc", PARAMETERISED)
    write(tmp_path, "p.yaml", "---\nx:\n  label: label is 2\n---\n---\nx:\n  label: label is 3\n---\n")
    done = run_cli("x.osc", "--scenario-parameter-file", "p.yaml", cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert "label is 1" not in done.stdout
    assert done.stdout.index("label is 2") < done.stdout.index("label is 3")
    assert "Executing scenario 'x-0'" in done.stdout and "Executing scenario 'x-1'" in done.stdout
    assert "x-2" not in done.stdout
    write(tmp_path, "one.yaml", "---\nx:\n  label: label is 2\n---\n")
    single = run_cli("x.osc", "--scenario-parameter-file", "one.yaml", cwd=tmp_path)
    assert "Executing scenario 'x'" in single.stdout and "x-0" not in single.stdout
    write(tmp_path, "none.yaml", "")
    empty = run_cli("x.osc", "--scenario-parameter-file", "none.yaml", cwd=tmp_path)
    assert empty.returncode == 0 and "label is 1" in empty.stdout
