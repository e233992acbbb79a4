"""Find where a value stands in a JSON text, to point a validation error at its line and column.

``json.loads`` forgets positions, which is right for the fast path; only when a document turns out
to be invalid is its text walked again, along the path of the bad value, to find it.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

_WHITESPACE = " \t\n\r"
_DECODER = json.JSONDecoder()


def _skip(text: str, pos: int) -> int:
    while pos < len(text) and text[pos] in _WHITESPACE:
        pos += 1
    return pos


def _step_object(text: str, pos: int, key: str) -> int | None:
    pos = _skip(text, pos + 1)
    while pos < len(text) and text[pos] == '"':
        name, pos = _DECODER.raw_decode(text, pos)   # the key, a JSON string
        pos = _skip(text, pos)
        if pos >= len(text) or text[pos] != ":":
            return None
        pos = _skip(text, pos + 1)
        if name == key:
            return pos
        _, pos = _DECODER.raw_decode(text, pos)
        pos = _skip(text, pos)
        if pos < len(text) and text[pos] == ",":
            pos = _skip(text, pos + 1)
    return None


def _step_array(text: str, pos: int, index: int) -> int | None:
    pos = _skip(text, pos + 1)
    count = 0
    while pos < len(text) and text[pos] != "]":
        if count == index:
            return pos
        _, pos = _DECODER.raw_decode(text, pos)
        pos = _skip(text, pos)
        if pos < len(text) and text[pos] == ",":
            pos = _skip(text, pos + 1)
        count += 1
    return None


def line_column(text: str, pos: int) -> tuple[int, int]:
    """1-based line and column of offset ``pos``."""
    line = text.count("\n", 0, pos) + 1
    column = pos - (text.rfind("\n", 0, pos) + 1) + 1
    return line, column


def locate(text: str, path: Sequence[str | int]) -> tuple[int, int] | None:
    """Line and column of the value at ``path`` (keys and indices), or of its deepest existing parent.

    Returns None when the text is not JSON at all. Only used on errors, so it favours simplicity.
    """
    try:
        pos = _skip(text, 0)
        for step in path:
            if pos >= len(text):
                break
            found: int | None = None
            if text[pos] == "{" and isinstance(step, str):
                found = _step_object(text, pos, step)
            elif text[pos] == "[" and isinstance(step, int):
                found = _step_array(text, pos, step)
            if found is None:
                break
            pos = found
        return line_column(text, pos)
    except (ValueError, IndexError):
        return None
