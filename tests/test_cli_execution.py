"""The real ``scenario_execution`` command, run as a subprocess on small scenario files."""

from __future__ import annotations

import signal
import subprocess
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from cli_support import EXE, needs_frontend, run_cli

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
    assert suite.get("failures") == "1" and names == ["Parsing of UNKNOWN.osc"]


@needs_frontend
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


@needs_frontend
def test_action_without_implementation_is_an_error_even_in_dry_run(tmp_path):
    write(tmp_path, "s.osc", HELPERS + "action no_plugin_here:\n    p: string = 'x'\n"
                                       "scenario s:\n    do no_plugin_here()\n")
    done = run_cli("s.osc", "-n", cwd=tmp_path)
    assert done.returncode == 1 and "Traceback" not in done.stdout
    assert "no_plugin_here" in done.stdout and "scenario_execution.actions" in done.stdout
    assert done.stdout.startswith("s.osc:")


@needs_frontend
def test_dry_run_and_log_model_execute_nothing(tmp_path):
    write(tmp_path, "s.osc", HELPERS + "scenario s:\n    do log('executed')\n")
    done = run_cli("s.osc", "-n", "-l", "-o", "out", cwd=tmp_path)
    assert done.returncode == 0 and "executed" in done.stdout  # the model mentions it …
    assert "[INFO]" not in done.stdout and not (tmp_path / "out/test.xml").exists()  # … nothing ran


@needs_frontend
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


@needs_frontend
def test_post_run_hooks_in_order_after_test_xml(tmp_path):
    write(tmp_path, "s.osc", HELPERS + "scenario s:\n    do log('x')\n")
    hook = write(tmp_path, "hook.sh", '#!/bin/sh\necho "$0 $1 $(test -f "$1/test.xml" && echo xml)" >> calls.txt\n'
                                      "exit 3\n")
    hook.chmod(0o755)
    done = run_cli("s.osc", "-o", "out", "--post-run", "./hook.sh", "--post-run", "sh ./hook.sh", cwd=tmp_path)
    lines = (tmp_path / "calls.txt").read_text().splitlines()
    assert lines == [f"./hook.sh {tmp_path / 'out'} xml", f"./hook.sh {tmp_path / 'out'} xml"]
    assert "exit code 3" in done.stdout


@needs_frontend
def test_sigterm_records_aborted_and_ends_children(tmp_path):
    write(tmp_path, "long.osc", HELPERS + "scenario long:\n    do serial:\n        log('started')\n"
                                          "        run_process('sleep 61.25')\n")
    process = subprocess.Popen([EXE, "long.osc", "-o", "out"], cwd=tmp_path, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
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
    assert root.find(".//failure").get("message") == "aborted"
