"""How a command's process ends (cli.boundary): the run's garbage is finalized, the rest is not scanned again.

An ending interpreter collects its garbage over every object it still holds, more than once, which
cost a batch process 0.1 s of CPU (benchmarks/bench_batch_process.py measures the batch's own CPU).
A command run as a process's entry point collects once and freezes what is left; checked here in a
real process: a reference cycle made by the run still has its ``__del__`` called, and what is left is
frozen once the last exit function has run.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

#: A command whose run leaves a reference cycle with a finalizer; an exit function registered before the
#: command starts (so it runs last) says whether the objects left were frozen. Automatic collection is
#: off, so only the collections of the interpreter's end can finalize the cycle.
SCRIPT = """
import atexit, gc, sys
from pathlib import Path

import click

from cli.boundary import Boundary

gc.disable()
atexit.register(lambda: print("frozen", gc.get_freeze_count() > 0, flush=True))


class Cycle:
    def __init__(self, path):
        self.path, self.me = path, self

    def __del__(self):
        Path(self.path).write_text("finalized")


@click.command()
@click.argument("path")
def command(path):
    Cycle(path)
    return 0


Boundary("ends").main(command, [sys.argv[1]])
"""


def test_a_command_process_finalizes_the_garbage_of_its_run_and_freezes_what_is_left(tmp_path: Path) -> None:
    marker = tmp_path / "finalized.txt"
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(marker)], capture_output=True, text=True, timeout=60,
                          cwd=Path(__file__).resolve().parent.parent)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["frozen True"]
    assert marker.read_text() == "finalized", "a reference cycle of the run lost its __del__ at the end"
