"""``-o`` names a device, a FIFO or standard output: written in place, never replaced (issue 32 item 2).

The devices are made by each test in its own folder (``mknod`` of ``/dev/null``'s numbers, as root, and
a FIFO), never the machine's ``/dev/null``.
"""

from __future__ import annotations

import os
import stat
import threading

import pytest
from coverage_support import BIN, coverage, run

pytest_plugins = ["coverage_fixtures"]


def _null_device(folder) -> str:
    path = folder / "null"
    try:
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("making a character device needs root (CI runs as root)")
    return str(path)


def _reading_fifo(folder) -> tuple[str, list[bytes], threading.Thread]:
    path = folder / "fifo"
    os.mkfifo(path)
    received: list[bytes] = []

    def drain() -> None:
        with open(path, "rb") as handle:
            received.append(handle.read())

    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    return str(path), received, reader


COMMANDS = [("report",), ("json",), ("html",)]


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: c[0])
def test_a_character_device_stays_a_device(child_batch, tmp_path, command):
    null = _null_device(tmp_path)
    done = coverage(*command, str(child_batch.results), "-o", null, cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    assert stat.S_ISCHR(os.lstat(null).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["null"]          # no temporary file left either


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: c[0])
def test_a_fifo_is_written_into_and_stays_a_fifo(child_batch, tmp_path, command):
    fifo, received, reader = _reading_fifo(tmp_path)
    done = coverage(*command, str(child_batch.results), "-o", fifo, cwd=tmp_path)
    reader.join(timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert received and (b"cut_in" in received[0])


def test_a_fifo_nobody_reads_is_an_error_not_a_hang(child_batch, tmp_path):
    os.mkfifo(tmp_path / "fifo")
    done = coverage("json", str(child_batch.results), "-o", str(tmp_path / "fifo"), cwd=tmp_path)
    assert done.returncode == 1 and str(tmp_path / "fifo") in done.stderr and "Traceback" not in done.stderr


def test_dash_is_standard_output(child_batch, tmp_path):
    for command in COMMANDS:
        done = coverage(*command, str(child_batch.results), "-o", "-", cwd=tmp_path)
        assert done.returncode == 0 and "cut_in" in done.stdout, done.stderr
    assert list(tmp_path.iterdir()) == []


def test_the_batch_report_to_a_device_a_fifo_and_standard_output(child_batch, tmp_path):
    batch = str(BIN / "scenario_batch_execution")
    null = _null_device(tmp_path)
    done = run(batch, "report", "--store", child_batch.store, "-o", null, cwd=tmp_path)
    assert stat.S_ISCHR(os.lstat(null).st_mode), done.stdout + done.stderr
    fifo, received, reader = _reading_fifo(tmp_path)
    run(batch, "report", "--store", child_batch.store, "-o", fifo, cwd=tmp_path)
    reader.join(timeout=60)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and b"<testsuites" in received[0]
    out = run(batch, "report", "--store", child_batch.store, "-o", "-", cwd=tmp_path)
    assert out.stdout.startswith("<?xml") and "job(s)" in out.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo", "null"]
