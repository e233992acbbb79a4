"""Every input is bounded (issue 32 item 4): a scenario file's size, the lines a message quotes, the
size of a covering array, and each long computation answers Ctrl-C and SIGTERM."""

from __future__ import annotations

import os

from coverage_support import BIN, run

HELLO = 'import osc.helpers\nscenario s:\n    do serial:\n        log("x")\n'


def test_a_stray_huge_scenario_file_is_refused_before_it_is_read(tmp_path):
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "ok.osc").write_text(HELLO, encoding="utf-8")
    with open(tmp_path / "in" / "huge.osc", "wb") as handle:     # 500 MB, sparse: one line, no newline
        handle.write(b"scenario s:" + b"x" * 1000)
        handle.truncate(500 * 1024 * 1024)
    done = run(str(BIN / "scenario_batch_execution"), "-i", "in", "-o", "results", "--store",
               f"sqlite:///{tmp_path / 's.db'}", cwd=tmp_path)
    assert done.returncode == 1
    log = tmp_path / "results" / "huge" / "log.txt"
    assert log.stat().st_size < 4096, log.read_bytes()[:2000]
    assert "larger than the limit of 64 MiB for a scenario file" in log.read_text(encoding="utf-8")
    assert len(done.stdout) + len(done.stderr) < 20_000
    assert (tmp_path / "results" / "ok" / "test.xml").is_file()
    assert os.path.getsize(tmp_path / "results" / "test.xml") < 20_000
