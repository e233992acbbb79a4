"""The shell examples of the documentation run as tests (Sybil collects every ``console`` block).

A ``console`` block is a shell session: lines starting with ``$ `` are commands, the lines under one
are what its output must contain, in order (``...`` stands for anything, within a line or for whole
lines). Each page runs in its own temporary folder holding ``examples/`` (a link to the repository's,
which the examples only read), with this interpreter's commands first on ``PATH``. A command must
exit 0 unless its line ends with ``# exit N``. A command that cannot run here (an install, a database
or a launch file of the reader's) is written in an ``sh`` block, which is shown and never run, with its
placeholders named in a comment; ``<!-- skip: next -->`` skips a ``console`` block.

Sybil is the well-kept tool for this (it runs code blocks of Markdown and reST through pytest, with
custom evaluators for other languages); prysk would need the sessions moved into ``.t`` files, and
pytest-markdown-docs runs only Python blocks.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from sybil import Sybil
from sybil.parsers.markdown import CodeBlockParser, SkipParser

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
_EXIT = re.compile(r"#\s*exit\s+(\d+)\s*$")


def run_session(example) -> None:
    """Run the commands of one ``console`` block and check their exit codes and output."""
    folder = example.namespace["folder"]
    for command, expected in _commands(example.parsed):
        wanted = _EXIT.search(command)
        env = dict(os.environ, PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}", NO_COLOR="1",
                   COLUMNS="200", PYTHONPATH=str(ROOT))
        env.pop("SCENARIO_STORE", None)
        done = subprocess.run(["bash", "-c", command], cwd=folder, env=env, capture_output=True, text=True,
                              timeout=300)
        output = done.stdout + done.stderr
        code = int(wanted.group(1)) if wanted else 0
        assert done.returncode == code, f"$ {command}\nexit {done.returncode}, expected {code}\n{output}"
        _expect(command, expected, output)


def _commands(text: str) -> list[tuple[str, list[str]]]:
    found: list[tuple[str, list[str]]] = []
    for line in text.splitlines():
        if line.startswith("$ "):
            found.append((line[2:], []))
        elif found and line.strip():
            found[-1][1].append(line.rstrip())
    return found


def _expect(command: str, expected: list[str], output: str) -> None:
    """Each expected line must match a later output line (``...`` matches anything)."""
    lines = output.splitlines()
    position = 0
    for want in expected:
        if want.strip() == "...":
            continue
        pattern = re.compile(".*".join(re.escape(part) for part in want.split("...")))
        while position < len(lines) and not pattern.fullmatch(lines[position].rstrip()):
            position += 1
        assert position < len(lines), f"$ {command}\nmissing in the output: {want!r}\n--- output ---\n{output}"
        position += 1


def _setup(namespace: dict) -> None:
    folder = Path(tempfile.mkdtemp(prefix="docs_example_"))
    (folder / "examples").symlink_to(ROOT / "examples")
    namespace["folder"] = folder


def _teardown(namespace: dict) -> None:
    shutil.rmtree(namespace["folder"], ignore_errors=True)


pytest_collect_file = Sybil(
    parsers=[CodeBlockParser(language="console", evaluator=run_session), SkipParser()],
    patterns=["*.md"],
    setup=_setup,
    teardown=_teardown,
).pytest()
