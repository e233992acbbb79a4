"""The front end's caches hold pickles: only the user's own private files are ever loaded (issue 11 item 1).

Each test lets ``scenario_execution -n`` fill a cache folder, replaces every cache file with a pickle
that would create a marker file when loaded, makes the file or its folder untrustworthy in one way,
and runs again: the run must succeed (the data is rebuilt) and the marker must not appear.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HELLO = ROOT / "examples" / "hello_world" / "hello_world.osc"


class _Planted:
    """Loading this pickle runs ``touch`` on the marker path."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


def dry_run(cache: Path, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT), SCENARIO_CACHE_DIR=str(cache))
    return subprocess.run([sys.executable, "-m", "cli.scenario_execution", "-n", str(HELLO)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=60)


def fill_and_plant(tmp_path: Path, cache: Path) -> tuple[list[Path], Path]:
    assert dry_run(cache, tmp_path).returncode == 0
    files = sorted(p for p in cache.iterdir() if p.is_file())
    assert files, "the first run should have written its caches"
    marker = tmp_path / "planted-code-ran"
    payload = pickle.dumps(_Planted(marker))
    for path in files:
        path.write_bytes(payload)
    return files, marker


def test_the_cache_folder_is_private_and_its_own_files_load(tmp_path):
    cache = tmp_path / "cache"
    files, marker = fill_and_plant(tmp_path, cache)
    assert cache.stat().st_mode & 0o777 == 0o700
    result = dry_run(cache, tmp_path)           # the control: a private file of ours IS loaded
    assert marker.exists(), result.stderr


def test_a_file_others_can_write_is_ignored(tmp_path):
    cache = tmp_path / "cache"
    files, marker = fill_and_plant(tmp_path, cache)
    for path in files:
        path.chmod(0o666)
    result = dry_run(cache, tmp_path)
    assert result.returncode == 0, result.stderr
    assert not marker.exists()


def test_a_folder_others_can_write_is_not_used(tmp_path):
    cache = tmp_path / "cache"
    files, marker = fill_and_plant(tmp_path, cache)
    cache.chmod(0o777)
    result = dry_run(cache, tmp_path)
    assert result.returncode == 0, result.stderr
    assert not marker.exists()


def test_a_symbolic_link_in_the_cache_is_ignored(tmp_path):
    cache = tmp_path / "cache"
    files, marker = fill_and_plant(tmp_path, cache)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    for path in files:
        target = elsewhere / path.name
        path.rename(target)
        path.symlink_to(target)
    result = dry_run(cache, tmp_path)
    assert result.returncode == 0, result.stderr
    assert not marker.exists()


def test_a_file_of_another_user_is_ignored(tmp_path):
    cache = tmp_path / "cache"
    files, marker = fill_and_plant(tmp_path, cache)
    if os.geteuid() == 0:
        for path in files:
            os.chown(path, 65534, 65534)        # nobody: as if planted by another account
        result = dry_run(cache, tmp_path)
    else:                                       # as a normal user: run as if we were another user
        env_uid = os.getuid()
        assert all(p.stat().st_uid == env_uid for p in files)
        result = subprocess.run(
            [sys.executable, "-c", "import os, runpy, sys; os.getuid = lambda: 65534; sys.argv = sys.argv[1:]; "
             "runpy.run_module('cli.scenario_execution', run_name='__main__')", "x", "-n", str(HELLO)],
            cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(ROOT), SCENARIO_CACHE_DIR=str(cache)),
            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert not marker.exists()


def test_nothing_is_read_from_the_shared_temporary_folder(tmp_path):
    """The old place (``/tmp/.osc_lalr_*``) is not looked at any more."""
    cache = tmp_path / "cache"
    assert dry_run(cache, tmp_path).returncode == 0
    shared = tmp_path / "tmp"
    shared.mkdir()
    env = dict(os.environ, PYTHONPATH=str(ROOT), TMPDIR=str(shared), SCENARIO_CACHE_DIR=str(cache))
    subprocess.run([sys.executable, "-m", "cli.scenario_execution", "-n", str(HELLO)], cwd=tmp_path, env=env,
                   capture_output=True, timeout=60, check=True)
    assert list(shared.iterdir()) == []
