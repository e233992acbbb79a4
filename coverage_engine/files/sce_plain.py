"""The ``.sce`` files ``scenario_variation`` writes, read without a YAML parser.

A ``.sce`` is YAML, and :func:`coverage_engine.files.sce.parse_sce` reads any YAML a user may have
edited it into. But nearly every file it reads is one our writer made, line for line in one shape:
header comments, ``key: scalar`` lines, an ``assignment:`` block of ``"key": scalar`` lines, and the
model as a ``|2`` literal block. Building a YAML parser's objects for that costs a batch job about a
millisecond and, in a job forked from a warm server, the copying of some 300 memory pages the parser
touches. :func:`load_plain` reads that one shape in a few string operations and gives the same
mapping YAML would; anything it is not certain about (an escape in a string, a number YAML might
read another way, a flow mapping, a character YAML treats specially, a repeated key) makes it
return None, and the caller reads the file with YAML as before. So it is never a second opinion on
YAML's rules: only a shortcut for text whose meaning both agree on. The tests compare the two.
"""

from __future__ import annotations

import re

#: A double-quoted string YAML and we read alike: no escape, no quote inside.
_STRING = re.compile(r'"([^"\\]*)"')
#: Integers as we write them (YAML 1.1 would read ``012`` as octal and ``1_000`` as 1000: not ours).
_INT = re.compile(r"-?(?:0|[1-9][0-9]*)")
#: Floats as we write them: a plain decimal (an exponent or ``.inf`` goes to YAML).
_FLOAT = re.compile(r"-?[0-9]+\.[0-9]+")
#: What YAML reads differently from plain text anywhere in a file: line breaks other than ``\n``
#: (CR, NEL, LS, PS), a byte order mark, characters it does not accept. (The writer keeps a model
#: holding any of them out of a literal block.)
YAML_SPECIAL = re.compile("[^\t\n\x20-\x7e\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]|[\x85\u2028\u2029\ufeff]")
_NOT_SURE = object()
#: The keys our writer gives a file (YAML 1.1 reads ``yes``, ``null`` or ``1_0`` as keys of other types).
_KEYS = ("format_version", "source", "source_sha256", "source_dir", "scenario", "index", "assignment", "model")


def _scalar(text: str) -> object:
    """The value of a scalar as we write it, or ``_NOT_SURE``."""
    match = _STRING.fullmatch(text)
    if match is not None:
        return match.group(1)
    if _INT.fullmatch(text):
        return int(text)
    if _FLOAT.fullmatch(text):
        return float(text)
    if text in ("true", "false"):
        return text == "true"
    return _NOT_SURE


def load_plain(text: str) -> dict | None:
    """The mapping YAML would read from ``text``, when ``text`` has the shape our writer gives a
    ``.sce``; None otherwise (read it with YAML)."""
    if YAML_SPECIAL.search(text) is not None:
        return None
    lines = text.split("\n")
    data: dict = {}
    position = 0
    while position < len(lines):
        line = lines[position]
        position += 1
        if not line or line.startswith("#"):
            continue
        key, colon, rest = line.partition(": ")
        if not colon:
            if line == "assignment:":
                key, rest = "assignment", ""
            else:
                return None
        if key in data or key not in _KEYS:
            return None
        if key == "model":
            if rest != "|2":
                return None
            model, position = _literal_block(lines, position)
            if model is None or any(ln and not ln.startswith("#") for ln in lines[position:]):
                return None                   # something after the model: not our shape
            data[key] = model
            return data
        if key == "assignment":
            if rest == "{}":
                data[key] = {}
                continue
            if rest:
                return None
            assignment: dict = {}
            while position < len(lines) and lines[position].startswith("  "):
                name, colon, value = lines[position][2:].partition(": ")
                match = _STRING.fullmatch(name)
                scalar = _scalar(value)
                if not colon or match is None or scalar is _NOT_SURE or match.group(1) in assignment:
                    return None
                assignment[match.group(1)] = scalar
                position += 1
            if not assignment:
                return None                   # "assignment:" alone is null to YAML (and refused)
            data[key] = assignment
            continue
        scalar = _scalar(rest)
        if scalar is _NOT_SURE:
            return None
        data[key] = scalar
    return None                               # no model: let YAML say what is wrong


def _literal_block(lines: list[str], position: int) -> tuple[str | None, int]:
    """The text of a ``|2`` literal block starting at ``lines[position]`` (clip chomping), and the
    position after it; None when a line is one YAML would read in another way."""
    content: list[str] = []
    while position < len(lines):
        line = lines[position]
        if line.startswith("  ") and line.strip(" "):
            content.append(line[2:])
        elif line == "":
            content.append("")
        elif line.startswith("#"):
            break                            # a comment at column 0 ends the block
        else:
            return None, position
        position += 1
    else:
        # The text ends inside the block: YAML keeps a missing last line break missing. Our files
        # close the block with their end line; anything else is YAML's to read.
        return None, position
    while content and content[-1] == "":
        content.pop()
    return ("\n".join(content) + "\n" if content else ""), position
