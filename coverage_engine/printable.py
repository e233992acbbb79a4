"""The one helper that makes text from a file or a name safe to print, in every command.

A scenario, variant, job or file name, a value recorded in a result, a source line quoted in an
error: any of them may hold ESC, CSI or OSC sequences (clear the screen, recolour the terminal, write
the clipboard with OSC 52), carriage returns that hide what came before, or bytes that are not UTF-8.
:func:`printable` writes every such character as a visible escape (``\\x1b``); :func:`clipped` keeps a
line of any length to a window around the column that matters, so a 500 MB one-line file never
reaches a terminal or a log.
"""

from __future__ import annotations

import re

#: The most characters of a quoted source line shown in a message (a window around the column of interest).
MAX_SHOWN = 200
#: The most characters of any one line of a message (a name, a path, a value quoted in it).
MAX_MESSAGE_LINE = 1000

_SURROGATES = range(0xDC80, 0xDD00)


def printable(text: str) -> str:
    """``text`` safe to print on a terminal: control characters (ESC, bell, carriage return…) and bytes
    that are not UTF-8 (kept by the file system as surrogates) are shown as escapes, never sent raw."""
    if text.isprintable():
        return text
    out = []
    for char in text:
        if ord(char) in _SURROGATES:
            out.append(f"\\x{ord(char) - 0xDC00:02x}")
        elif char.isprintable():
            out.append(char)
        else:
            out.append(char.encode("unicode_escape", "backslashreplace").decode("ascii"))
    return "".join(out)


def printable_lines(text: str, width: int = MAX_MESSAGE_LINE) -> str:
    """Each line of ``text`` :func:`clipped` to ``width`` and made :func:`printable` (line breaks kept)."""
    return "\n".join(printable(clipped(line, 1, width)[0]) for line in text.split("\n"))


def clipped(line: str, column: int = 1, width: int = MAX_SHOWN) -> tuple[str, int]:
    """At most ``width`` characters of ``line`` around ``column`` (1-based), ``…`` where it was cut;
    returns the shown text and the column's place in it."""
    if len(line) <= width:
        return line, column
    start = max(0, min(column - 1 - width // 2, len(line) - width))
    shown = line[start:start + width]
    head = "…" if start > 0 else ""
    tail = "…" if start + width < len(line) else ""
    return head + shown + tail, column - start + len(head)


#: Characters XML 1.0 cannot carry (and PostgreSQL text cannot hold NUL); replaced before writing.
_ILLEGAL_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def clean_text(text: str) -> str:
    """``text`` without the characters XML 1.0 (and PostgreSQL) refuse, each replaced by U+FFFD: what a
    name becomes in a JUnit report (so a reader matches a folder's name to its testsuite this way)."""
    return _ILLEGAL_XML.sub("\ufffd", text)


def surrogates_escaped(text: str) -> str:
    """``text`` (a file name) with the bytes that are not UTF-8 (kept as surrogates) written ``\\xff``:
    the text a store, a report and a JSON document can hold."""
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
