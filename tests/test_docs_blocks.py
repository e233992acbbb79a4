"""Every shell example in ``docs/`` is either run by the tests or marked as not run (issue 22).

``docs/conftest.py`` runs the ``console`` sessions. Any other block holding a command (``sh``, ``bash``,
``shell`` or no language) must follow a ``<!-- not run: why -->`` line, so a reader knows which names
are theirs; output and diagrams are ``text`` blocks. A page cannot grow an unmarked, untested example.
"""

from __future__ import annotations

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parent.parent / "docs"
FENCE = re.compile(r"^```(\S*)\s*$")
MARK = re.compile(r"^<!-- not run: .+ -->$")


def blocks(path: Path):
    """``(language, first line number, lines, the nearest non-blank line before the block)``."""
    lines = path.read_text(encoding="utf-8").splitlines()
    inside, language, start, body, before = False, "", 0, [], ""
    for number, line in enumerate(lines, 1):
        match = FENCE.match(line)
        if match and not inside:
            inside, language, start, body = True, match.group(1), number, []
            before = next((lines[i] for i in range(number - 2, -1, -1) if lines[i].strip()), "")
        elif line.startswith("```") and inside:
            inside = False
            yield language, start, body, before
        elif inside:
            body.append(line)


def test_every_command_block_runs_or_says_why_not():
    unmarked = []
    for page in sorted(DOCS.glob("*.md")):
        for language, start, _body, before in blocks(page):
            if language in ("sh", "bash", "shell", "") and not MARK.match(before.strip()):
                unmarked.append(f"{page.name}:{start} ({language or 'no language'})")
    assert not unmarked, "command blocks neither run (console) nor marked <!-- not run: why -->: " + ", ".join(unmarked)


def test_the_pages_have_sessions_that_run():
    sessions = [page.name for page in DOCS.glob("*.md") for language, *_ in blocks(page) if language == "console"]
    assert {"index.md", "variation.md", "batch.md", "coverage.md", "pytest.md", "exit-codes.md"} <= set(sessions)
