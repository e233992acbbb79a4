"""Several scenario files and folders in one command (issue 22 item 3), through the real CLIs."""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from batch_fixtures import child_command, cli_env, run_cli, write_child, write_scenarios
from cli_support import run_variation

BIN = Path(sys.executable).parent
ONE = "import osc.helpers\nscenario {name}:\n    do serial:\n        log() with:\n            keep(it.msg in ['a', 'b'])\n"


def vary(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    return run_variation(tmp_path, *args, timeout=120)


def test_variation_takes_files_and_folders_into_one_output(tmp_path):
    (tmp_path / "cut.osc").write_text(ONE.format(name="cut"))
    (tmp_path / "more").mkdir()
    (tmp_path / "more" / "merge.osc").write_text(ONE.format(name="merge"))
    (tmp_path / "more" / "turn.osc").write_text(ONE.format(name="turn"))
    done = vary(tmp_path, "cut.osc", "more")
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in (tmp_path / "out").glob("*.sce")) == [
        "cut0.sce", "cut1.sce", "merge0.sce", "merge1.sce", "turn0.sce", "turn1.sce"]


def test_one_bad_file_stops_only_itself(tmp_path):
    (tmp_path / "good.osc").write_text(ONE.format(name="good"))
    (tmp_path / "bad.osc").write_text("scenario bad:\n    do serial:\n        log(\n")
    done = vary(tmp_path, "bad.osc", "good.osc")
    assert done.returncode == 1
    assert done.stderr.startswith("bad.osc:")
    assert sorted(p.name for p in (tmp_path / "out").glob("*.sce")) == ["good0.sce", "good1.sce"]


def test_batch_takes_several_input_folders_and_subfolders(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "a", {"one": "xml=pass"})
    write_scenarios(tmp_path / "b", {"two": "xml=pass"})
    write_scenarios(tmp_path / "b" / "deeper", {"three": "xml=pass"})
    env = cli_env(tmp_path)
    both = run_cli(["-i", "a", "-i", "b", "-o", "r1", "--", *child_command(child)], tmp_path, env)
    assert both.returncode == 0, both.stderr
    names = [c.get("name") for c in ET.parse(tmp_path / "r1" / "test.xml").getroot().iter("testcase")]
    assert names == ["one", "two"]
    deep = run_cli(["-i", "a", "-i", "b", "--recursive", "-o", "r2", "--", *child_command(child)], tmp_path, env)
    assert deep.returncode == 0, deep.stderr
    names = [c.get("name") for c in ET.parse(tmp_path / "r2" / "test.xml").getroot().iter("testcase")]
    assert names == ["one", "two", "three"]
    write_scenarios(tmp_path / "c", {"one": "xml=pass"})
    clash = run_cli(["-i", "a", "-i", "c", "-o", "r3", "--", *child_command(child)], tmp_path, env)
    assert clash.returncode == 1 and "share a name, their output folders would collide" in clash.stderr


def test_a_file_name_that_is_not_utf8_fails_alone(tmp_path):
    """Issue 21 item 5: one such name used to stop the whole batch (and variation) with an internal error."""
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"fine": "xml=pass"})
    (tmp_path / "in" / os.fsdecode(b"bad\xff.sce")).write_text("xml=pass\n")
    done = run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, cli_env(tmp_path))
    assert done.returncode == 1
    assert "internal error" not in done.stderr and "Traceback" not in done.stderr
    assert "bad\\xff.sce: the file name is not UTF-8" in done.stderr
    cases = {c.get("name"): c for c in ET.parse(tmp_path / "results" / "test.xml").getroot().iter("testcase")}
    assert cases["fine"].find("failure") is None and cases["fine"].find("error") is None
    assert cases["bad\\xff"].find("failure") is not None or cases["bad\\xff"].find("error") is not None

    (tmp_path / "good.osc").write_text(ONE.format(name="good"))
    (tmp_path / os.fsdecode(b"odd\xfe.osc")).write_text(ONE.format(name="odd"))
    varied = vary(tmp_path, "good.osc", os.fsdecode(b"odd\xfe.osc"))
    assert varied.returncode == 1
    assert "odd\\xfe.osc: the file name is not UTF-8" in varied.stderr and "internal error" not in varied.stderr
    assert sorted(p.name for p in (tmp_path / "out").glob("*.sce")) == ["good0.sce", "good1.sce"]


def test_jobs_record_the_real_paths_of_linked_input_folders_and_files(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "real_in", {"a": "xml=pass"})
    write_scenarios(tmp_path / "elsewhere", {"target": "xml=pass"})
    (tmp_path / "real_in" / "b.sce").symlink_to(tmp_path / "elsewhere" / "target.sce")
    (tmp_path / "in").symlink_to(tmp_path / "real_in", target_is_directory=True)
    done = run_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, cli_env(tmp_path))
    assert done.returncode == 0, done.stdout + done.stderr
    files = {suite.get("name"): {p.get("name"): p.get("value") for p in suite.iter("property")}["scenario_file"]
             for suite in ET.parse(tmp_path / "results" / "test.xml").getroot().iter("testsuite")}
    real = tmp_path.resolve()
    assert files == {"a": str(real / "real_in" / "a.sce"), "b": str(real / "elsewhere" / "target.sce")}
