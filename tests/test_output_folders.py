"""Folders we create stay under their output root, and a run that cannot run is never silent.

Issue 11 item 3 (symbolic links lead out of the output folder) and issue 21 item 6 (a bad
``_output_dir`` in a later parameter document): through the real ``scenario_execution`` and
``scenario_batch_execution``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from batch_fixtures import child_command, cli_env, run_cli, write_child, write_scenarios

EXE = str(Path(sys.executable).parent / "scenario_execution")
SCENARIO = "import osc.helpers\nscenario s:\n    do serial:\n        log('ran')\n"


def execute(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([EXE, *args], cwd=tmp_path, capture_output=True, text=True, timeout=60,
                          env=dict(os.environ, NO_COLOR="1"))


def write(tmp_path: Path, parameters: str) -> None:
    (tmp_path / "s.osc").write_text(SCENARIO)
    (tmp_path / "p.yaml").write_text(parameters)


def test_a_link_inside_the_output_folder_cannot_lead_out_of_it(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    (tmp_path / "res").mkdir()
    (tmp_path / "res" / "link").symlink_to(outside)
    write(tmp_path, "s: {_output_dir: link/sub}\n")
    done = execute(tmp_path, "s.osc", "-o", "res", "--scenario-parameter-file", "p.yaml")
    assert done.returncode == 1
    assert done.stderr.startswith("p.yaml:1:5: error: 's._output_dir': 'link/sub' leads out of the output directory")
    assert "Traceback" not in done.stderr
    assert list(outside.iterdir()) == []


def test_a_bad_folder_in_a_later_document_runs_nothing(tmp_path):
    write(tmp_path, "s: {}\n---\ns: {_output_dir: " + "x" * 300 + "}\n")
    done = execute(tmp_path, "s.osc", "-o", "res", "--scenario-parameter-file", "p.yaml")
    assert done.returncode == 1
    assert done.stderr.startswith("p.yaml:3:5: error: 's._output_dir': the path is too long")
    assert "ran" not in done.stdout + done.stderr


def test_a_folder_that_cannot_be_created_is_an_error_testcase(tmp_path):
    (tmp_path / "blocker").write_text("a file, not a folder")
    write(tmp_path, "s: {}\n---\ns: {_output_dir: " + str(tmp_path / "blocker") + "/sub}\n")
    done = execute(tmp_path, "s.osc", "-o", "res", "--scenario-parameter-file", "p.yaml")
    assert done.returncode == 1
    assert "cannot be a folder" in done.stderr and "Traceback" not in done.stderr


def test_a_run_whose_folder_fails_at_run_time_is_an_error_and_the_others_run(tmp_path):
    write(tmp_path, "s: {}\n---\ns: {_output_dir: /proc/no-such-folder}\n")
    done = execute(tmp_path, "s.osc", "-o", "res", "--scenario-parameter-file", "p.yaml")
    assert done.returncode == 1
    assert "Traceback" not in done.stderr and "internal error" not in done.stderr
    suite = ET.parse(tmp_path / "res" / "test.xml").getroot().find("testsuite")
    assert suite is not None
    assert (suite.get("tests"), suite.get("errors"), suite.get("failures")) == ("2", "1", "0")
    error = suite.find("testcase[@name='s-1']/error")
    assert error is not None and "cannot create the output directory '/proc/no-such-folder'" in error.get("message", "")


def test_a_job_folder_planted_as_a_link_is_not_written_through(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"good": "xml=pass", "planted": "xml=pass"})
    victim = tmp_path / "victim"
    victim.mkdir()
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "planted").symlink_to(victim)
    done = run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, cli_env(tmp_path))
    assert done.returncode == 1, done.stdout + done.stderr
    assert list(victim.iterdir()) == []
    assert "symbolic link" in done.stdout + done.stderr
    cases = {c.get("name"): c for c in ET.parse(tmp_path / "results" / "test.xml").getroot().iter("testcase")}
    assert cases["good"].find("failure") is None and cases["good"].find("error") is None
    assert cases["planted"].find("error") is not None


def test_a_result_that_is_a_link_to_a_secret_is_never_read(tmp_path):
    """Issue 11 item 5: a child (or a neighbour) making test.xml or log.txt a link cannot leak a file."""
    secret = tmp_path / "secret.txt"
    secret.write_text("<testsuite><testcase name='TOPSECRET'/></testsuite>")
    write_scenarios(tmp_path / "in", {"sneaky": "x"})
    script = (f"ln -s {secret} {{OUTPUT_DIR}}/test.xml; rm -f {{OUTPUT_DIR}}/log.txt; "
              f"ln -s {secret} {{OUTPUT_DIR}}/log.txt; echo {{SCENARIO}} > /dev/null")
    done = run_cli(["-i", "in", "-o", "results", "--", "sh", "-c", script], tmp_path, cli_env(tmp_path))
    assert done.returncode == 1, done.stdout + done.stderr
    report = (tmp_path / "results" / "test.xml").read_text()
    assert "TOPSECRET" not in report and "TOPSECRET" not in done.stdout + done.stderr
    assert "test.xml is a symbolic link: not followed" in report


def test_a_result_left_as_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    """A child leaving test.xml and log.txt as FIFOs: the batch must not wait in open() for a writer that
    never comes; the job is an error that says why, and the batch ends."""
    write_scenarios(tmp_path / "in", {"piped": "x"})
    script = ("rm -f {OUTPUT_DIR}/log.txt; mkfifo {OUTPUT_DIR}/log.txt {OUTPUT_DIR}/test.xml; "
              "echo {SCENARIO} > /dev/null")
    done = run_cli(["-i", "in", "-o", "results", "--timeout", "60", "--", "sh", "-c", script], tmp_path,
                   cli_env(tmp_path))
    assert done.returncode == 1, done.stdout + done.stderr
    error = ET.parse(tmp_path / "results" / "test.xml").getroot().find(".//testcase/error")
    assert error is not None and "test.xml is not a regular file" in error.get("message", "")


def test_a_file_planted_where_a_job_folder_goes_is_left_alone_and_the_rest_runs(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"filed": "xml=pass", "fine": "xml=pass"})
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "filed").write_text("not a folder\n")
    done = run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, cli_env(tmp_path))
    assert done.returncode == 1, done.stdout + done.stderr
    assert "Traceback" not in done.stderr
    assert (tmp_path / "results" / "filed").read_text() == "not a folder\n"
    cases = {c.get("name"): c for c in ET.parse(tmp_path / "results" / "test.xml").getroot().iter("testcase")}
    assert cases["fine"].find("error") is None and cases["fine"].find("failure") is None
    filed = cases["filed"].find("error")
    assert filed is not None and "exists and is not a folder" in filed.get("message")
