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

from coverage_engine.printable import printable

__all__ = ["printable", "wants_rich"]


def wants_rich(stream: TextIO | None = None) -> bool:
    """Whether ``stream`` (default stdout) gets rich output."""
    stream = stream or sys.stdout
    if os.environ.get("TERM") == "dumb":
        return False
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False
