"""How a command's process ends (cli.boundary): with one garbage collection where no one else's code runs.

An ending interpreter collects its garbage over every object it still holds, more than once, which
cost a batch process 0.1 s of CPU (``benchmarks/bench_batch_process.py`` measures the batch's own CPU).
A command that runs no one else's Python in its process (the batch, the coverage reports) collects
once and freezes what is left; one that runs plugins and external methods (``scenario_execution``,
``scenario_variation``, ``scenario_search``) ends as any interpreter does, so what a plugin still holds
at the end is finalized. Checked in real processes.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: An exit function registered before the command starts runs after the command's own: it says whether
#: the objects left were frozen. Automatic collection is off, so only the collections of the
#: interpreter's end can finalize a reference cycle.
PREAMBLE = """
import atexit, gc, sys
from pathlib import Path

gc.disable()
atexit.register(lambda: print("frozen", gc.get_freeze_count() > 0, flush=True))


class Cycle:
    def __init__(self, path):
        self.path, self.me = path, self

    def __del__(self):
        Path(self.path).write_text("finalized")
"""

#: A command whose run leaves a reference cycle, garbage by the time it ends (``held``: or one that a
#: module still holds then, as a plugin's cache would).
COMMAND = PREAMBLE + """
import click

from cli.boundary import Boundary

HELD = []


@click.command()
@click.argument("path")
@click.argument("held")
def command(path, held):
    cycle = Cycle(path)
    if held == "held":
        HELD.append(cycle)
    return 0


Boundary("ends", quick_end=sys.argv[3] == "quick").main(command, sys.argv[1:3])
"""


def _run(code: str, *args: str) -> list[str]:
    done = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    return [line for line in done.stdout.splitlines() if line.startswith("frozen")]


def test_a_quick_end_finalizes_the_garbage_of_the_run_and_freezes_what_is_left(tmp_path: Path) -> None:
    marker = tmp_path / "finalized.txt"
    assert _run(COMMAND, str(marker), "garbage", "quick") == ["frozen True"]
    assert marker.read_text() == "finalized", "a reference cycle of the run lost its __del__ at the end"


def test_a_command_that_runs_plugins_ends_as_an_interpreter_does(tmp_path: Path) -> None:
    """What a module still holds at the end (a plugin's cache, a recorder) is finalized as the modules go."""
    marker = tmp_path / "finalized.txt"
    assert _run(COMMAND, str(marker), "held", "plain") == ["frozen False"]
    assert marker.read_text() == "finalized"


@pytest.mark.parametrize(("module", "quick"), [
    ("scenario_batch_execution", True), ("scenario_coverage", True),
    ("scenario_execution", False), ("scenario_variation", False), ("scenario_search", False),
])
def test_only_the_commands_that_run_no_one_elses_code_end_quickly(module: str, quick: bool) -> None:
    code = PREAMBLE + f"from cli.{module} import main\nmain(['--help'])\n"
    assert _run(code) == [f"frozen {quick}"]
