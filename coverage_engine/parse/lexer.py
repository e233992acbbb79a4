"""A hand-written lexer for the ``.osc`` grammar, feeding the LALR driver of :mod:`coverage_engine.parse.lalr`.

Why not lark's own contextual lexer: it costs about 3 µs per token (and importing lark ~15 ms), too
much for the 80 ms budget of a whole ``scenario_execution -n`` run and for files of thousands of lines. This one dispatches on the
first character to one precompiled regex and keeps line/column by hand. It is still *contextual*
for keywords: a word becomes a keyword only where the parser state accepts that keyword, so
``unit`` or ``offset`` remain ordinary names elsewhere, as with lark's contextual lexer. Terminal
names and keyword strings are taken from the grammar, so ``grammar.lark`` stays the one definition.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import NoReturn

from coverage_engine.parse.lalr import ParseFailure
from coverage_engine.parse.tables import NAME_RE, Tables

QUOTED_NAME_RE = re.compile(r"\|[^|\r\n]+\|")
#: Numbers are ASCII digits (``str.isdigit`` also accepts '²' and '①', which no number is made of).
NUMBER_RE = re.compile(r"0[xX][0-9a-fA-F]+|\d*\.\d+(?:[eE][+-]?\d+)?|\d+", re.ASCII)
#: String literals, each alternative written as an "unrolled loop" (a run of ordinary characters, then
#: one escape or lone quote and another run): the regex engine keeps no state per character, so a
#: 50 MB literal costs its own size, not the ~115 bytes per character of ``(?:a|b)*``.
STRING_RE = re.compile(
    r'"""[^"\\]*(?:(?:\\[\s\S]|"(?!""))[^"\\]*)*"""'
    r"|'''[^'\\]*(?:(?:\\[\s\S]|'(?!''))[^'\\]*)*'''"
    r'|"[^"\\\r\n]*(?:\\(?:\r\n|[\s\S])[^"\\\r\n]*)*"'
    r"|'[^'\\\r\n]*(?:\\(?:\r\n|[\s\S])[^'\\\r\n]*)*'"
)
NEWLINE_RE = re.compile(r"(?:(?:\r\n|\r|\n)[\t \f]*|#[^\r\n]*)+")
BLANK_RE = re.compile(r"[\t \f]+")
CONTINUATION_RE = re.compile(r"\\[\t \f]*(?:\r\n|\r|\n)")
BLOCK_COMMENT_RE = re.compile(r"/\*[\s\S]*?\*/")
LINE_BREAK_RE = re.compile(r"\r\n|\r|\n")



class Token:
    """One token: its terminal name, text and position (1-based line/column, 0-based offsets)."""

    __slots__ = ("type", "value", "start_pos", "line", "column", "end_line", "end_column", "end_pos")

    def __init__(self, type: str, value: str, start_pos: int, line: int, column: int,  # noqa: A002
                 end_line: int, end_column: int, end_pos: int) -> None:
        self.type, self.value, self.start_pos = type, value, start_pos
        self.line, self.column, self.end_line, self.end_column, self.end_pos = (
            line, column, end_line, end_column, end_pos)

    def __str__(self) -> str:
        return self.value

    def __repr__(self) -> str:
        return f"Token({self.type!r}, {self.value!r}, {self.line}:{self.column})"


_new_token = Token


def _breaks(text: str) -> tuple[int, int]:
    """Number of line breaks in ``text`` and the offset just after the last one (-1 if none)."""
    count, last = 0, -1
    for match in LINE_BREAK_RE.finditer(text):
        count += 1
        last = match.end()
    return count, last


class AdjacentLiterals(Exception):
    """``7 -1``: a value, a blank, then a signed literal (ASAM lexes ``-1`` as one literal): no operator."""

    def __init__(self, message: str, line: int, column: int) -> None:
        super().__init__(message)
        self.message, self.line, self.column = message, line, column


#: Words after which ``-1`` is an operand, not a second value (``x and -1``, ``keep(it in -1)``).
_OPERATOR_WORDS = frozenset({"and", "or", "not", "in", "is", "return", "if", "else", "then"})


def _signed_literal_after_value(text: str, pos: int) -> bool:
    """Whether the ``-`` at ``pos`` starts a signed literal right after a value with a blank between them."""
    if not "0" <= text[pos + 1:pos + 2] <= "9":       # an empty slice is below "0"
        return False
    before = pos
    while before > 0 and text[before - 1] in " \t":
        before -= 1
    if before == pos or before == 0:
        return False
    previous = text[before - 1]
    if previous in ")]\"'":
        return True
    if not (previous.isalnum() or previous == "_"):
        return False
    start = before
    while start > 0 and (text[start - 1].isalnum() or text[start - 1] == "_"):
        start -= 1
    return text[start:before] not in _OPERATOR_WORDS


class OscLexer:
    """Tokens of one text; a word is a keyword only where the current parser state accepts it."""

    def __init__(self, tables: Tables) -> None:
        self.states = tables.states
        self.punctuation = tables.punctuation
        self.keywords = tables.keywords
        self.two_char = {p for p in self.punctuation if len(p) == 2}

    def lex(self, text: str, state_box: list[int]) -> Iterator[Token]:
        """Yield the tokens of ``text``; ``state_box[0]`` is the parser's current state."""
        states = self.states
        keywords, punctuation, two_char = self.keywords, self.punctuation, self.two_char
        pos, line, line_start, length = 0, 1, 0, len(text)
        while pos < length:
            char = text[pos]
            if char == " " or char == "\t" or char == "\f":
                pos = BLANK_RE.match(text, pos).end()  # type: ignore[union-attr]  # a blank was just seen
                continue
            column = pos - line_start + 1
            if char.isalpha() or char == "_":
                match = NAME_RE.match(text, pos)
                if match is None:  # a letter-like char that \w does not accept
                    self._fail(pos, line, column, state_box)
                end = match.end()
                value = match.group()
                kind = keywords.get(value)
                if kind is None or kind not in states[state_box[0]]:
                    kind = "NAME"
                yield _new_token(kind, value, pos, line, column, line, column + end - pos, end)
                pos = end
                continue
            if "0" <= char <= "9" or (char == "." and "0" <= text[pos + 1:pos + 2] <= "9"
                                      and text[pos - 1:pos] != "."):
                match = NUMBER_RE.match(text, pos)
                assert match is not None  # a digit (or '.' and a digit) was just seen
                end = match.end()
                value = match.group()
                if value[:2] in ("0x", "0X"):
                    kind = "HEX"
                elif "." in value:
                    kind = "FLOAT"
                else:
                    kind = "INT"
                yield _new_token(kind, value, pos, line, column, line, column + end - pos, end)
                pos = end
                continue
            if char == "\n" or char == "\r" or char == "#":
                end = NEWLINE_RE.match(text, pos).end()  # type: ignore[union-attr]  # a newline or '#' was just seen
                value = text[pos:end]
                count, last = _breaks(value)
                end_line = line + count
                end_column = (end - (pos + last) + 1) if last >= 0 else column + end - pos
                yield _new_token("_NL", value, pos, line, column, end_line, end_column, end)
                if last >= 0:
                    line, line_start = end_line, pos + last
                pos = end
                continue
            if char == '"' or char == "'":
                match = STRING_RE.match(text, pos)
                if match is None:
                    self._fail(pos, line, column, state_box)
                end = match.end()
                value = match.group()
                count, last = _breaks(value)
                if count:
                    end_line, end_column = line + count, end - (pos + last) + 1
                else:
                    end_line, end_column = line, column + end - pos
                yield _new_token("STRING", value, pos, line, column, end_line, end_column, end)
                if count:
                    line, line_start = end_line, pos + last
                pos = end
                continue
            if char == "|":
                match = QUOTED_NAME_RE.match(text, pos)
                if match is None:
                    self._fail(pos, line, column, state_box)
                end = match.end()
                yield _new_token("NAME", match.group(), pos, line, column, line, column + end - pos, end)
                pos = end
                continue
            if char == "\\" or (char == "/" and text.startswith("/*", pos)):
                match = (CONTINUATION_RE if char == "\\" else BLOCK_COMMENT_RE).match(text, pos)
                if match is None:
                    self._fail(pos, line, column, state_box)
                count, last = _breaks(match.group())
                if count:
                    line, line_start = line + count, pos + last
                pos = match.end()
                continue
            pair = text[pos:pos + 2]
            if pair in two_char:
                yield _new_token(punctuation[pair], pair, pos, line, column, line, column + 2, pos + 2)
                pos += 2
                continue
            kind = punctuation.get(char)
            if kind is None:
                self._fail(pos, line, column, state_box)
            if char == "-" and _signed_literal_after_value(text, pos):
                raise AdjacentLiterals(
                    "two values without an operator between them: ASAM reads '-' followed by a digit as the "
                    "sign of a literal; write 'a - 1' (subtraction) or 'a - -1'", line, column)
            yield _new_token(kind, char, pos, line, column, line, column + 1, pos + 1)
            pos += 1

    def _fail(self, pos: int, line: int, column: int, state_box: list[int]) -> NoReturn:
        state = state_box[0]
        raise ParseFailure(state, set(self.states[state]), None, pos, line, column)
