"""``pytest --osc``: scenarios and variants as pytest items, in a real pytest subprocess (issue 17 item 2)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

GOOD = 'import osc.helpers\nscenario good:\n    do serial:\n        log("fine")\n'
BAD = 'import osc.helpers\nscenario bad:\n    gap: float = 0.5\n    do serial:\n        compare(gap, ">", 1.0)\n'
COVERED = ('import osc.helpers\nscenario covered:\n    speed: float = 3.0\n    cover(speed)\n'
           '    do serial:\n        log("x")\n')


def pytest_run(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env.pop("PYTEST_ADDOPTS", None)
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:randomly", *args], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=180)


def scenarios(tmp_path: Path) -> None:
    folder = tmp_path / "scen"
    folder.mkdir()
    (folder / "good.osc").write_text(GOOD)
    (folder / "bad.osc").write_text(BAD)
    (folder / "covered.osc").write_text(COVERED)
    (tmp_path / "test_unrelated.py").write_text("def test_unrelated():\n    assert True\n")


def test_collects_scenarios_as_items_named_after_them(tmp_path):
    scenarios(tmp_path)
    done = pytest_run(tmp_path, "--osc", "scen", "--collect-only", "-q")
    assert done.returncode == 0, done.stdout + done.stderr
    ids = [line for line in done.stdout.splitlines() if "::" in line]
    assert ids == ["scen/bad.osc::bad", "scen/covered.osc::covered", "scen/good.osc::good"]


def test_failures_carry_the_located_message_and_junit_and_coverage_work(tmp_path):
    scenarios(tmp_path)
    done = pytest_run(tmp_path, "--osc", "scen", "--junitxml", "report.xml")
    assert done.returncode == 1
    assert f"bad: 'compare' at {tmp_path / 'scen' / 'bad.osc'}:5:9 failed: 0.5 > 1.0 is False" in done.stdout
    assert "1 failed, 2 passed" in done.stdout
    cases = {c.get("name"): c for c in ET.parse(tmp_path / "report.xml").getroot().iter("testcase")}
    assert set(cases) == {"good", "bad", "covered"} and cases["bad"].find("failure") is not None
    coverage = json.loads((tmp_path / "osc-results" / "scen_covered.osc__covered" / "coverage.json").read_text())
    assert coverage["items"][0]["samples"] == [3.0]


def test_k_x_and_last_failed(tmp_path):
    scenarios(tmp_path)
    only = pytest_run(tmp_path, "--osc", "scen", "-k", "good")
    assert only.returncode == 0 and "1 passed, 2 deselected" in only.stdout
    stop = pytest_run(tmp_path, "--osc", "scen", "-x")
    assert stop.returncode == 1 and "1 failed" in stop.stdout and "passed" not in stop.stdout.splitlines()[-1]
    again = pytest_run(tmp_path, "--osc", "scen", "--lf")
    assert again.returncode == 1 and "run-last-failure: rerun previous 1 failure" in again.stdout
    assert again.stdout.splitlines()[-1].strip("= ").startswith("1 failed in")


def test_without_osc_nothing_changes(tmp_path):
    scenarios(tmp_path)
    done = pytest_run(tmp_path, "-q")
    assert done.returncode == 0 and "1 passed" in done.stdout            # only the ordinary test
    both = pytest_run(tmp_path, "-q", "test_unrelated.py", "--osc", "scen/good.osc")
    assert both.returncode == 0 and "2 passed" in both.stdout
    missing = pytest_run(tmp_path, "--osc", "nowhere")
    assert missing.returncode == 4 and "--osc nowhere: no such file or folder" in missing.stderr


def test_items_whose_ids_read_alike_get_folders_of_their_own(tmp_path):
    folder = tmp_path / "sc3"
    folder.mkdir()
    (folder / "x y.osc").write_text(GOOD.replace("good", "s"))
    (folder / "x_y.osc").write_text(COVERED.replace("covered", "s"))
    done = pytest_run(tmp_path, "--osc", "sc3", "-q")
    assert done.returncode == 0, done.stdout + done.stderr
    folders = sorted(p.name for p in (tmp_path / "osc-results").iterdir())
    assert len(folders) == 2 and all(name.startswith("sc3_x_y.osc__s-") for name in folders), folders
    logs = sorted((tmp_path / "osc-results" / name / "log.txt").is_file() for name in folders)
    coverage = [name for name in folders if (tmp_path / "osc-results" / name / "coverage.json").is_file()]
    assert logs == [True, True] and len(coverage) == 1
    (folder / "x y.osc").unlink()                        # alone, an item keeps its readable folder name
    assert pytest_run(tmp_path, "--osc", "sc3", "-q").returncode == 0
    assert (tmp_path / "osc-results" / "sc3_x_y.osc__s" / "coverage.json").is_file()


def test_a_timeout_ends_the_scenarios_whole_process_tree(tmp_path):
    folder = tmp_path / "scen"
    folder.mkdir()
    (folder / "hang.osc").write_text("import osc.helpers\nscenario hang:\n    do serial:\n"
                                     "        run_process('sleep 61.37')\n")
    done = pytest_run(tmp_path, "--osc", "scen", "--osc-timeout", "3", "-q")
    assert done.returncode == 1 and "timed out after 3 s" in done.stdout, done.stdout
    left = subprocess.run(["pgrep", "-f", "sleep 61.37"], capture_output=True, text=True)
    assert left.returncode != 0, f"orphans left: {left.stdout}"
    assert "aborted by SIGTERM" in (tmp_path / "osc-results" / "scen_hang.osc__hang" / "test.xml").read_text()
