"""A ``.sce`` file with a key written twice or a key we do not know is refused, located (issue 21 item 9)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = "import osc.helpers\nscenario s:\n    do serial:\n        log() with:\n            keep(it.msg in ['a', 'b'])\n"


def command(name: str, *args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(Path(sys.executable).parent / name), *args], cwd=cwd, capture_output=True, text=True,
                          timeout=60, env=dict(os.environ, NO_COLOR="1", PYTHONPATH=str(ROOT)))


def variant(tmp_path: Path) -> tuple[Path, list[str]]:
    (tmp_path / "s.osc").write_text(SCENARIO)
    assert command("scenario_variation", "s.osc", cwd=tmp_path).returncode == 0
    path = tmp_path / "out" / "s1.sce"
    return path, path.read_text().split("\n")


def test_a_duplicate_index_does_not_silently_win(tmp_path):
    path, lines = variant(tmp_path)
    at = lines.index("index: 1")
    lines.insert(at + 1, "index: 7")
    path.write_text("\n".join(lines))
    done = command("scenario_execution", "-n", "out/s1.sce", cwd=tmp_path)
    assert done.returncode == 1
    assert done.stderr.startswith(f"out/s1.sce:{at + 2}:1: error: malformed .sce file: duplicate key 'index' "
                                  f"(first at line {at + 1})")


def test_an_unknown_key_is_refused(tmp_path):
    path, lines = variant(tmp_path)
    at = lines.index("index: 1")
    lines.insert(at + 1, "retries: 3")
    path.write_text("\n".join(lines))
    done = command("scenario_execution", "-n", "out/s1.sce", cwd=tmp_path)
    assert done.returncode == 1
    assert done.stderr.startswith(f"out/s1.sce:{at + 2}:1: error: malformed .sce file: unknown key 'retries'")
    assert "Traceback" not in done.stderr


def test_a_duplicate_in_the_assignment_is_refused(tmp_path):
    path, lines = variant(tmp_path)
    at = next(i for i, line in enumerate(lines) if line.startswith('  "s.log.msg"'))
    lines.insert(at + 1, lines[at])
    path.write_text("\n".join(lines))
    done = command("scenario_execution", "-n", "out/s1.sce", cwd=tmp_path)
    assert done.returncode == 1
    assert "duplicate key 's.log.msg'" in done.stderr
