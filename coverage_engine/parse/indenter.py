"""Indentation post-lexer: turns newline tokens into ``_NL``/``_INDENT``/``_DEDENT`` for the LALR parser.

It plays the part of lark's :class:`~lark.indenter.Indenter` (same attributes and ``process``) without
importing lark, which the parser avoids at run time (see :mod:`coverage_engine.parse.lalr`), and differs in three ways:
newline tokens are made zero-width and placed right after the previous real token (so a rule that
ends with ``_NL`` ends exactly at its last character, which the variation generator relies on when
it cuts source by offsets); tabs advance to the next multiple of 8 as in the reference lexer; and a
dedent to a column that matches no open block is reported as our :class:`OscSyntaxError` with a
position instead of lark's ``DedentError``.
"""

from __future__ import annotations

from collections.abc import Iterator

from coverage_engine.errors import OscSyntaxError
from coverage_engine.location import Location
from coverage_engine.parse.lexer import Token

TAB_WIDTH = 8


def indentation_width(blanks: str) -> int:
    """Width of a run of leading blanks; a tab moves to the next multiple of :data:`TAB_WIDTH`."""
    width = 0
    for ch in blanks:
        if ch == "\t":
            width += TAB_WIDTH - (width % TAB_WIDTH)
        elif ch == " ":
            width += 1
    return width


class OscIndenter:
    """Post-lexer for the ``.osc`` grammar; ``file``/``text`` are set by the parser before each parse."""

    NL_type = "_NL"
    OPEN_PAREN_types = ["LPAR", "LSQB"]
    CLOSE_PAREN_types = ["RPAR", "RSQB"]
    INDENT_type = "_INDENT"
    DEDENT_type = "_DEDENT"
    tab_len = TAB_WIDTH

    def __init__(self) -> None:
        self.file = "<string>"
        self.text = ""

    def _anchor(self, kind: str, value: str, after: Token | None) -> Token:
        """A zero-width token of ``kind`` standing right after ``after`` (or at the file start)."""
        if after is None:
            return Token(kind, value, 0, 1, 1, 1, 1, 0)
        return Token(kind, value, after.end_pos, after.end_line, after.end_column,
                     after.end_line, after.end_column, after.end_pos)

    def process(self, stream: Iterator[Token]) -> Iterator[Token]:
        """Yield the tokens of ``stream`` with indentation tokens inserted; newlines in brackets dropped."""
        levels = [0]
        depth = 0
        last: Token | None = None
        for token in stream:
            kind = token.type
            if kind == "_NL":
                if depth > 0:
                    continue
                yield self._anchor("_NL", token.value, last)
                text = token.value
                cut = max(text.rfind("\n"), text.rfind("\r"))
                if cut < 0:  # a trailing comment with no newline after it: end of input follows
                    continue
                width = indentation_width(text[cut + 1:])
                if width > levels[-1]:
                    levels.append(width)
                    yield self._anchor("_INDENT", "", last)
                elif width < levels[-1]:
                    while width < levels[-1]:
                        levels.pop()
                        yield self._anchor("_DEDENT", "", last)
                    if width != levels[-1]:
                        self._bad_dedent(token, width, levels[-1])
                continue
            if kind in ("LPAR", "LSQB"):
                depth += 1
            elif kind in ("RPAR", "RSQB") and depth > 0:
                depth -= 1
            last = token
            yield token
        while len(levels) > 1:
            levels.pop()
            yield self._anchor("_DEDENT", "", last)

    def _bad_dedent(self, token: Token, width: int, expected: int) -> None:
        """Raise the error for a line indented to a column that closes no block exactly."""
        line = (token.end_line or token.line)
        column = len(token.value) - max(token.value.rfind("\n"), token.value.rfind("\r"))
        lines = self.text.splitlines()
        source = lines[line - 1] if 0 < line <= len(lines) else None
        raise OscSyntaxError(
            f"inconsistent indentation: this line is indented by {width}, which matches no enclosing "
            f"block (expected {expected} or a deeper block's indentation)",
            Location(self.file, line, column, line, column, token.end_pos, token.end_pos),
            source,
            "indent each block consistently; lines of one block must start in the same column",
        )
