"""The one place where lark's parse failures become our :class:`OscSyntaxError`.

The message names the offending token and what could have come instead in user words (``end of
line``, ``')'`` -- not ``_NL``/``RPAR``); the hint comes from lark's ``match_examples`` over
:data:`HINTS`, a table of labelled bad snippets (tested in ``tests/test_parser_errors.py``).
"""

from __future__ import annotations

from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from coverage_engine.errors import OscError, OscSyntaxError
from coverage_engine.syntax import Location

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
    from coverage_engine.parser import grammar

    try:
        pattern = grammar().get_terminal(name).pattern
    except KeyError:
        return name.lower()
    if pattern.type == "str":
        return f"'{pattern.value}'"
    return name.lower().replace("_", " ")


def _describe_token(token) -> str:
    kind = getattr(token, "type", "")
    if kind in ("_NL", "_INDENT", "_DEDENT", "$END"):
        return _WORDS[kind]
    value = str(token)
    if len(value) > 30:
        value = value[:27] + "..."
    return f"'{value}'"


def _expected(names) -> str:
    words = sorted({describe_terminal(n) for n in names})
    if not words:
        return ""
    if len(words) > 10:
        words = words[:10] + ["…"]
    return ", expected " + (words[0] if len(words) == 1 else "one of " + ", ".join(words))


def _hint(exc: UnexpectedInput) -> str | None:
    from coverage_engine.parser import _raw_parse

    def parse(snippet: str):
        try:
            return _raw_parse(snippet)
        except OscError:
            return None

    try:
        return exc.match_examples(parse, HINTS, use_accepts=True)
    except Exception:  # noqa: BLE001 - a hint is a nicety; never let it hide the real error
        return None


def syntax_error_from_lark(exc: UnexpectedInput, file: str, text: str) -> OscSyntaxError:
    """Our error for lark's ``exc``: location of the offending token, source line, message and hint."""
    line = max(getattr(exc, "line", 1) or 1, 1)
    column = max(getattr(exc, "column", 1) or 1, 1)
    start = getattr(exc, "pos_in_stream", None) or 0
    if isinstance(exc, UnexpectedToken):
        token = exc.token
        if token.type == "$END":
            message = "unexpected end of file" + _expected(exc.expected)
        else:
            message = f"unexpected {_describe_token(token)}" + _expected(exc.accepts or exc.expected)
        end = start + len(str(token))
    elif isinstance(exc, UnexpectedCharacters):
        char = text[start] if 0 <= start < len(text) else ""
        if char in "\"'":
            message = "unterminated string"
        else:
            message = f"unexpected character {char!r}" + _expected(exc.allowed or ())
        end = start + 1
    elif isinstance(exc, UnexpectedEOF):
        message = "unexpected end of file" + _expected(exc.expected)
        end = start
    else:  # pragma: no cover - lark has no other subclasses today
        message, end = str(exc), start
    lines = text.splitlines()
    if line > len(lines) and lines:
        line, column = len(lines), len(lines[-1]) + 1
    source_line = lines[line - 1] if 0 < line <= len(lines) else None
    location = Location(file, line, column, line, column + max(end - start, 0), start, end)
    return OscSyntaxError(message, location, source_line, _hint(exc))
