"""String literal decoding: quotes removed and escapes processed, Unicode text left untouched.

The reference decodes with ``unicode_escape``, which garbles non-ASCII characters; we process the
escapes Python knows (``\\n``, ``\\t``, ``\\xHH``, ``\\uXXXX``, ``\\N`` is not special …) on the text
itself and keep an unknown escape as written, as Python does.
"""

from __future__ import annotations

import re

_SIMPLE = {"n": "\n", "t": "\t", "r": "\r", "0": "\0", "a": "\a", "b": "\b", "f": "\f", "v": "\v",
           "\\": "\\", "'": "'", '"': '"'}
_ESCAPE = re.compile(r"\\(x[0-9a-fA-F]{2}|u[0-9a-fA-F]{4}|U[0-9a-fA-F]{8}|\r\n|[\s\S])")


def _replace(match: re.Match[str]) -> str:
    seq = match.group(1)
    if seq in _SIMPLE:
        return _SIMPLE[seq]
    if seq in ("\n", "\r", "\r\n"):
        return ""  # backslash-newline continues the string on the next line
    if len(seq) > 1 and seq[0] in "xuU":
        code = int(seq[1:], 16)
        if code <= 0x10FFFF:
            return chr(code)
    return match.group(0)


def unescape_string(token: str) -> str:
    """The value of a string token as written in the source (``'a\\tb'``, ``\"\"\"multi-line\"\"\"``)."""
    if token[:3] in ('"""', "'''") and len(token) >= 6:
        body = token[3:-3]
    else:
        body = token[1:-1]
    if "\\" not in body:
        return body
    return _ESCAPE.sub(_replace, body)
