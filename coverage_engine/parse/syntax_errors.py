"""The one place where parse failures become our :class:`~coverage_engine.errors.OscSyntaxError`.

The message names the offending token and what could have come instead in user words (``end of
line``, ``')'`` -- not ``_NL``/``RPAR``); the hint is the label of the snippet of :data:`HINTS`, a
table of labelled bad snippets, that fails in the same parser state (lark's ``match_examples`` idea;
tested in ``tests/test_parser_errors.py``).
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from coverage_engine.errors import OscError, OscSyntaxError
from coverage_engine.location import Location
from coverage_engine.parse.lalr import ParseFailure
from coverage_engine.parse.raw import raw_parse
from coverage_engine.parse.tables import tables

_LINE_BREAK = re.compile(r"\r\n|\r|\n")

# hint -> snippets that fail in the same parser state as the mistake the hint explains
HINTS: dict[str, list[str]] = {
    "a declaration header ends with ':' before its indented body (scenario name:)": [
        "scenario test\n    do log('x')\n",
        "action test\n    a: int\n",
        "struct test\n    a: int\n",
        "actor test\n    a: int\n",
    ],
    "'do', 'with' and composition headers end with ':' (do serial:)": [
        "scenario test:\n    do serial\n        log('x')\n",
        "scenario test:\n    do parallel\n        log('x')\n",
        "scenario test:\n    do one_of\n        log('x')\n",
    ],
    "a bracket or parenthesis is not closed": [
        "scenario test:\n    do log('x'\n",
        "global a: int = (1 + 2\n",
        "enum e: [a, b\n",
    ],
    "use '==' to compare inside keep(); '=' only gives a default value": [
        "scenario test:\n    a: int with:\n        keep(it = 3)\n",
        "struct s:\n    a: int\n    keep(a = 3)\n",
    ],
    "the body of a declaration must be indented under its header": [
        "scenario test:\ndo log('x')\n",
        "struct s:\na: int\n",
    ],
    "this line is indented deeper than the block it belongs to": [
        "scenario test:\n    a: int\n        b: int\n",
        "scenario test:\n    do serial:\n        log('a')\n            log('b')\n",
    ],
    "a behaviour invocation needs parentheses, even without arguments: log()": [
        "scenario test:\n    do serial:\n        log\n",
        "scenario test:\n    do log\n",
    ],
    "a parameter needs a type: name: type = value": [
        "scenario test:\n    a = 3\n",
        "struct s:\n    a = 3\n",
    ],
    "string literals must be closed on the same line (use triple quotes for several lines)": [
        "scenario test:\n    do log('x)\n",
        'scenario test:\n    do log("x)\n',
    ],
    "'with:' starts an indented block; put each keep() or modifier on its own line below": [
        "scenario test:\n    do log('x') with: keep(it.msg == 'a')\n",
    ],
    "declarations start with import, type, unit, enum, struct, actor, action, scenario, modifier, extend or global": [
        "foo bar\n",
        "scenari test:\n    do log('x')\n",
    ],
    "named arguments are written name: value": [
        "scenario test:\n    do log(msg = 'x')\n",
    ],
    "imports must come before all declarations": [
        "struct s:\n    a: int\nimport osc.helpers\n",
    ],
}

_WORDS = {
    "_NL": "end of line",
    "_INDENT": "an indented block",
    "_DEDENT": "end of the indented block",
    "$END": "end of file",
    "NAME": "a name",
    "INT": "an integer",
    "HEX": "a hex integer",
    "FLOAT": "a number",
    "STRING": "a string",
}


def describe_terminal(name: str) -> str:
    """A terminal of the grammar in user words: ``'('`` for LPAR, ``end of line`` for _NL."""
    if name in _WORDS:
        return _WORDS[name]
    word = tables().terminal_words.get(name)
    return f"'{word}'" if word is not None else name.lower()


def _describe_token(token: object) -> str:
    kind = getattr(token, "type", "")
    if kind == "_INDENT":
        return "indentation"
    if kind in ("_NL", "_DEDENT", "$END"):
        return _WORDS[kind]
    value = str(token)
    if len(value) > 30:
        value = value[:27] + "..."
    return f"'{value}'"


def _is_terminal(name: str) -> bool:
    return name == "$END" or name.lstrip("_")[:1].isupper()


def _expected(names: Iterable[str]) -> str:
    names = [n for n in names if _is_terminal(n)]
    words = sorted({describe_terminal(n) for n in names if n != "$END"} |
                   ({"end of file"} if "$END" in names else set()))
    if not words:
        return ""
    if len(words) > 10:
        words = words[:10] + ["…"]
    return ", expected " + (words[0] if len(words) == 1 else "one of " + ", ".join(words))


def _signature(failure: ParseFailure) -> tuple[int, str | None]:
    return failure.state, getattr(failure.token, "type", None)


def hint_for(failure: ParseFailure) -> str | None:
    """The label of :data:`HINTS` whose snippet fails like ``failure`` (same state; same token first)."""
    state_only = None
    for label, snippets in HINTS.items():
        for snippet in snippets:
            try:
                raw_parse(snippet)
            except ParseFailure as other:
                if other.state != failure.state:
                    continue
                if _signature(other) == _signature(failure):
                    return label
                if state_only is None:
                    state_only = label
            except (OscError, RecursionError, ValueError):
                continue
    return state_only


def syntax_error(failure: ParseFailure, file: str, text: str) -> OscSyntaxError:
    """Our error for a parse failure: location of the offending token, source line, message, hint."""
    token = failure.token
    if token is None:  # the lexer found a character no token starts with
        start, line, column = failure.pos, failure.line, failure.column
        char = text[start] if 0 <= start < len(text) else ""
        if char in "\"'":
            message = "unterminated string"
        elif char == "|":
            message = "unterminated |quoted identifier|"
        else:
            message = f"unexpected character {char!r}" + _expected(failure.expected)
        end = start + 1
    else:
        start, line, column = token.start_pos, token.line, token.column
        end = token.end_pos
        if token.type == "$END":
            message = "unexpected end of file" + _expected(failure.expected)
        else:
            message = f"unexpected {_describe_token(token)}" + _expected(failure.expected)
    lines = _LINE_BREAK.split(text)
    if line > len(lines):
        line, column = len(lines), len(lines[-1]) + 1
    source_line = lines[line - 1] if 0 < line <= len(lines) else None
    location = Location(file, line, column, line, column + max(end - start, 0), start, end)
    # the hint table re-enters the parser: restore nothing, the caller is done with this text
    return OscSyntaxError(message, location, source_line, hint_for(failure))
