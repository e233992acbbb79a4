"""Every YAML we read is bounded: an alias bomb is one located error in milliseconds (issue 11 item 2)."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HELLO = ROOT / "examples" / "hello_world" / "hello_world.osc"

#: Nine lines, 9**9 (387 million) strings once the aliases are expanded.
BOMB_LINES = ['a: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]'] + [
    f"{name}: &{name} [{', '.join(['*' + prev] * 9)}]" for prev, name in zip("abcdefgh", "bcdefghi", strict=True)]
BOMB = "\n".join(BOMB_LINES) + "\n"
#: 512 MB of address space: far more than a bounded run needs, far less than an expanded bomb.
MEMORY_LIMIT = 512 * 1024 * 1024


def limited() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def run(module: str, *args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT), NO_COLOR="1")
    return subprocess.run([sys.executable, "-m", module, *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=60, preexec_fn=limited)


def test_a_parameter_file_bomb_is_refused_at_its_line(tmp_path):
    (tmp_path / "bomb.yaml").write_text(BOMB)
    done = run("cli.scenario_execution", str(HELLO), "--scenario-parameter-file", "bomb.yaml", cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert done.stderr.startswith("bomb.yaml:7:4: error: this YAML stands for more than 1,000,000 values")
    assert "Traceback" not in done.stderr


def test_a_sce_bomb_is_refused(tmp_path):
    (tmp_path / "v.sce").write_text("# scenario_variation .sce, format 1\n" + BOMB.replace("a:", "format_version: 1\na:", 1))
    done = run("cli.scenario_execution", "v.sce", "-n", cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert "this YAML stands for more than 1,000,000 values" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_plan_bomb_is_refused(tmp_path):
    (tmp_path / "run").mkdir()
    (tmp_path / "plan.yaml").write_text("items:\n  x:\n    weight: 1\n" + BOMB)
    done = run("cli.scenario_coverage", "report", "run", "--plan", "plan.yaml", cwd=tmp_path)
    assert done.returncode != 0
    assert "this YAML stands for more than 1,000,000 values" in done.stderr + done.stdout
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize("copies", [1, 200])
def test_ordinary_aliases_still_work(tmp_path, copies):
    (tmp_path / "words.osc").write_text('import osc.helpers\nscenario s:\n    words: list of string = ["x"]\n'
                                       "    do serial:\n        log(words)\n")
    (tmp_path / "params.yaml").write_text("s: {words: [&w hello" + ", *w" * copies + "]}\n")
    done = run("cli.scenario_execution", "words.osc", "--scenario-parameter-file", "params.yaml", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "['hello', " + "'hello', " * (copies - 1) + "'hello']" in done.stdout + done.stderr


def test_a_bomb_of_bytes_is_refused_by_scenario_variation(tmp_path):
    """50,000 aliases of one 4 MB string pass the node bound and stand for 200 GB (issue 32 item 4)."""
    (tmp_path / "bytes.yaml").write_text("big: &big " + "x" * (4 * 1024 * 1024) + "\nmany: ["
                                         + ", ".join(["*big"] * 50_000) + "]\n")
    done = run("cli.scenario_variation", str(HELLO), "--scenario-parameter-file", "bytes.yaml", "-o", "out",
               "--store", f"sqlite:///{tmp_path / 's.db'}", cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert done.stderr.startswith("bytes.yaml:2:7: error: this YAML stands for more than 64 MiB of text")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").glob("*.sce"))
