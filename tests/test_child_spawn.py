"""A launched child that opens its own log (``executor/children/spawn.py``): what Popen gave it, it still gets."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from executor.children.process import ChildProcess
from executor.children.spawn import can_spawn_logged, spawn_logged

#: Says its session, its stdin, a variable of the extra environment and one of the parent's, on both streams.
SCRIPT = ('echo "sid $(cut -d" " -f6 /proc/$$/stat) pid $$"; read -r line || echo "stdin empty"; '
          'echo "extra $EXTRA home $HOME" >&2; exit 3')


def test_the_child_writes_its_own_log_in_its_own_session_with_the_environment(tmp_path: Path) -> None:
    log = tmp_path / "log.txt"
    log.write_text("earlier\n")
    process = spawn_logged(["sh", "-c", SCRIPT], str(log), append=False, extra_environment={"EXTRA": "x1"})
    assert process.wait() == 3 and process.poll() == 3
    lines = log.read_text().splitlines()
    sid, pid = lines[0].split()[1], lines[0].split()[3]
    assert sid == pid == str(process.pid)                      # a session (and process group) of its own
    assert lines[1:] == ["stdin empty", f"extra x1 home {os.environ.get('HOME', '')}"]   # truncated, not appended


def test_an_appended_log_keeps_what_was_there_and_a_missing_command_raises(tmp_path: Path) -> None:
    log = tmp_path / "log.txt"
    log.write_text("earlier\n")
    assert spawn_logged(["sh", "-c", "echo later"], str(log), append=True, extra_environment={}).wait() == 0
    assert log.read_text() == "earlier\nlater\n"
    with pytest.raises(FileNotFoundError):
        spawn_logged(["no-such-command-here"], str(log), append=True, extra_environment={})


def test_child_process_uses_it_in_this_folder_only(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "elsewhere").mkdir()
    assert can_spawn_logged(None) and can_spawn_logged(str(tmp_path))
    assert not can_spawn_logged(str(tmp_path / "elsewhere")) and not can_spawn_logged(str(tmp_path / "gone"))
    for cwd in (str(tmp_path), str(tmp_path / "elsewhere")):     # the second through Popen: same outcome
        child = ChildProcess(["sh", "-c", "pwd; exit 2"], str(tmp_path / "log.txt"), cwd=cwd, marker="7.1")
        assert child.start() is not None
        assert child.wait().returncode == 2
        assert (tmp_path / "log.txt").read_text() == f"{cwd}\n"
