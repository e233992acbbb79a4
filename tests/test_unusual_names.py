"""Unusual file names in a batch's results: an ESC, bytes that are not UTF-8 (issue 32 items 6 and 9).

Reading the results folder and reading the store give the same report; a job whose input name is not
UTF-8 is an error testcase that says so.
"""

from __future__ import annotations

import json
import os
import shutil

from coverage_support import BIN, coverage, run

HELLO = b'import osc.helpers\nscenario s:\n    do serial:\n        log("x")\n'


def _batch(tmp_path, names: list[bytes]) -> str:
    folder = os.path.join(os.fsencode(tmp_path), b"in")
    os.mkdir(folder)
    for name in names:
        with open(os.path.join(folder, name), "wb") as handle:
            handle.write(HELLO)
    url = f"sqlite:///{tmp_path / 'store.db'}"
    run(str(BIN / "scenario_batch_execution"), "-i", "in", "-o", "results", "--store", url, cwd=tmp_path)
    return url


def _json(tmp_path, *args: str) -> dict:
    done = coverage("json", *args, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    doc.pop("source")
    return doc


def test_an_escape_in_a_name_is_one_run_and_the_folder_reads_as_the_store(tmp_path):
    url = _batch(tmp_path, [b"a\x1bb.osc", b"ok.osc"])
    folder, store = _json(tmp_path, "results"), _json(tmp_path, "--store", url)
    assert folder["runs"]["total"] == 2 and folder["complete"] is True, folder
    assert folder == store


def test_a_name_that_is_not_utf8_is_an_error_saying_so_and_every_report_is_written(tmp_path):
    url = _batch(tmp_path, [b"c\xff.osc", b"ok.osc"])
    xml = (tmp_path / "results" / "test.xml").read_text(encoding="utf-8")
    assert "is not UTF-8" in xml and "no such file" not in xml
    folder, store = _json(tmp_path, "results"), _json(tmp_path, "--store", url)
    assert folder == store and folder["runs"]["error"] == 1 and folder["runs"]["passed"] == 1
    # a folder some other tool left there, its name not UTF-8: every report is still written
    shutil.copytree(tmp_path / "results" / "c\\xff", os.fsdecode(os.fsencode(tmp_path / "results") + b"/d\xfe"))
    for command in (["html", "-o", "page.html"], ["json", "-o", "doc.json"], ["report"]):
        done = coverage(command[0], "results", *command[1:], cwd=tmp_path)
        assert done.returncode == 0 and "internal error" not in done.stderr, done.stderr
    assert json.loads((tmp_path / "doc.json").read_text(encoding="utf-8"))["runs"]["total"] == 3
