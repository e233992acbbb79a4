"""The one terminal policy of every command: rich output (progress bars, tables, live views) or plain lines.

Rich output only on a real terminal with a capable ``TERM``; ``NO_COLOR`` (https://no-color.org)
asks for no colour and nothing else, so the display stays and rich drops its colours (it reads
``NO_COLOR`` itself). Everywhere else (pipes, files, CI logs) plain lines that a script can read. Files we write
are always plain.
"""

from __future__ import annotations

import os
import sys
from typing import TextIO


def wants_rich(stream: TextIO | None = None) -> bool:
    """Whether ``stream`` (default stdout) gets rich output."""
    stream = stream or sys.stdout
    if os.environ.get("TERM") == "dumb":
        return False
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


def printable(text: str) -> str:
    """``text`` safe to print on a terminal: control characters (ESC, bell, carriage return…) and bytes
    that are not UTF-8 (kept by the file system as surrogates) are shown as escapes, never sent raw."""
    if text.isprintable():
        return text
    out = []
    for char in text:
        if char.isprintable() and not 0xDC80 <= ord(char) <= 0xDCFF:
            out.append(char)
        elif 0xDC80 <= ord(char) <= 0xDCFF:
            out.append(f"\\x{ord(char) - 0xDC00:02x}")
        else:
            out.append(char.encode("unicode_escape").decode("ascii"))
    return "".join(out)
