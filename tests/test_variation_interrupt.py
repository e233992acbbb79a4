"""Stopping a long ``scenario_variation`` (SIGINT, SIGTERM), its progress lines and its size limit.

Real command in a subprocess, real files, a real SQLite store: after a stop every ``.sce`` on disk
has its row, and nothing is printed as a traceback.
"""

from __future__ import annotations

import hashlib
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _keeps(count: int, values: int = 3) -> str:
    """A scenario with ``count`` invocations, each varying over ``values`` strings."""
    listed = ", ".join(f'"{chr(97 + i)}"' for i in range(values))
    steps = "".join(f"        log() with:\n            keep(it.msg in [{listed}])\n" for _ in range(count))
    return f"import osc.helpers\n\nscenario big:\n    do serial:\n{steps}"


def _env() -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT), NO_COLOR="1", PYTHONUNBUFFERED="1")
    env.pop("SCENARIO_STORE", None)
    return env


def _rows(db: Path) -> dict:
    with sqlite3.connect(db) as conn:
        return {
            "variants": conn.execute("SELECT count(*) FROM variants").fetchone()[0],
            "runs": conn.execute("SELECT count(*), sum(variant_count) FROM variation_runs").fetchone(),
            "sources": conn.execute("SELECT count(*) FROM source_files").fetchone()[0],
            "hashes": {row[0]: row[1] for row in conn.execute("SELECT file_path, content_hash FROM variants")},
        }


@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_stop_keeps_a_row_for_every_file_and_prints_progress(tmp_path, signum):
    (tmp_path / "k.osc").write_text(_keeps(12))  # 531441 combinations: far more than written before the stop
    proc = subprocess.Popen([sys.executable, "-m", "cli.scenario_variation", "k.osc", "-o", "out"], cwd=tmp_path,
                            env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines = []
    deadline = time.monotonic() + 60
    for line in proc.stdout:  # stdout is a pipe, not a terminal: plain progress lines every few seconds
        lines.append(line)
        if line.startswith("... ") or time.monotonic() > deadline:
            break
    progress = lines[-1]
    assert progress.startswith("... ") and " of 531441 combinations" in progress, lines
    assert "/s, about " in progress and " left" in progress
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err + out and "Exception ignored" not in err + out
    name = signal.Signals(signum).name
    assert f"interrupted ({name}): wrote " in err
    written = int(err.split("wrote ", 1)[1].split(" ", 1)[0])
    files = sorted((tmp_path / "out").glob("*.sce"))
    assert 0 < written == len(files) < 531441
    rows = _rows(tmp_path / ".scenario_store.db")
    assert rows["variants"] == written and rows["runs"] == (1, written) and rows["sources"] == 1
    for path in files[:: max(1, len(files) // 50)]:  # each written file is recorded, with its content
        assert rows["hashes"][str(path.resolve())] == hashlib.sha256(path.read_bytes()).hexdigest()


def test_too_many_combinations_are_refused(tmp_path):
    (tmp_path / "k.osc").write_text(_keeps(15))  # 14348907 > 10,000,000
    for extra in ([], ["--list"]):
        result = subprocess.run([sys.executable, "-m", "cli.scenario_variation", "k.osc", *extra], cwd=tmp_path,
                                env=_env(), capture_output=True, text=True, timeout=60)
        assert result.returncode == 1
        assert "k.osc: error: 14348907 combinations" in result.stderr
        assert "--max-variants (10000000)" in result.stderr and "--max-variants 14348907" in result.stderr
        assert "Traceback" not in result.stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / ".scenario_store.db").exists()


def test_max_variants_option(tmp_path):
    (tmp_path / "k.osc").write_text(_keeps(2))  # 9 combinations
    args = [sys.executable, "-m", "cli.scenario_variation", "k.osc", "--max-variants"]
    refused = subprocess.run([*args, "8"], cwd=tmp_path, env=_env(), capture_output=True, text=True, timeout=60)
    assert refused.returncode == 1 and "9 combinations (3 x 3) are more than --max-variants (8)" in refused.stderr
    allowed = subprocess.run([*args, "9"], cwd=tmp_path, env=_env(), capture_output=True, text=True, timeout=60)
    assert allowed.returncode == 0, allowed.stderr
    assert len(list((tmp_path / "out").glob("*.sce"))) == 9
