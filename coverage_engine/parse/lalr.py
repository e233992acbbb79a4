"""The LALR driver: runs the tables of :mod:`~coverage_engine.parse.tables` over a token stream.

On every reduction it calls the syntax builder's method of the rule's name, so no intermediate tree
is built. A parse failure is a :class:`ParseFailure` carrying the parser state, which
:mod:`coverage_engine.parse.syntax_errors` turns into our error.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, Protocol

from coverage_engine.parse.tables import tables


class LexedToken(Protocol):
    """A token as the driver and the syntax error see it: its terminal's name and its place (the lexer's
    ``Token``, whose module imports this one for :class:`ParseFailure`, or the end-of-input token)."""

    @property
    def type(self) -> str: ...
    @property
    def line(self) -> int: ...
    @property
    def column(self) -> int: ...
    @property
    def start_pos(self) -> int: ...
    @property
    def end_pos(self) -> int: ...


class ParseFailure(Exception):
    """Raised by the lexer or driver: ``token`` (or a bad character at ``pos``) in parser ``state``."""

    def __init__(self, state: int, expected: set[str], token: LexedToken | None = None, pos: int = 0,
                 line: int = 1, column: int = 1) -> None:
        super().__init__("parse failure")
        self.state, self.expected, self.token = state, expected, token
        self.pos, self.line, self.column = pos, line, column


class _EndToken:
    """The end-of-input token, placed right after the last real token."""

    type = "$END"

    def __init__(self, last: LexedToken | None) -> None:
        self.value = ""
        self.line = getattr(last, "end_line", 1) or 1
        self.column = getattr(last, "end_column", 1) or 1
        self.start_pos = self.end_pos = getattr(last, "end_pos", 0) or 0
        self.end_line, self.end_column = self.line, self.column

    def __str__(self) -> str:
        return ""


class _Inline(list):
    """Children of an inlined (``_name``) rule, spliced into the parent's children."""


_bound_rules: dict[int, list] = {}


def _splice(inline: tuple[bool, ...], children: list[object]) -> _Inline:
    """``children`` with the inlined ones spliced in. A left-recursive list (``_declaration*`` is
    ``list: list item | item``) grows its first child in place: that child is off the value stack
    already, and copying it at every item made a file of n declarations cost n² (80,000 scenarios:
    84 s; a million: hours)."""
    if children and inline[0] and type(children[0]) is _Inline:
        spliced, start = children[0], 1
    else:
        spliced, start = _Inline(), 0
    assert isinstance(spliced, _Inline)
    for flag, child in zip(inline[start:], children[start:], strict=True):
        if flag and type(child) is _Inline:
            spliced.extend(child)
        else:
            spliced.append(child)
    return spliced


def _rules_of(builder: object) -> list[Any]:
    """Per rule of the table: ``builder``'s callback (None for inlined rules), goto symbol, length,
    expand1 and inline mask; bound once per builder."""
    rules = _bound_rules.get(id(builder))
    if rules is None:
        rules = _bound_rules[id(builder)] = [
            (None if name[0] == "_" else getattr(builder, name, None), origin, size, expand1, inline)
            for name, origin, size, expand1, inline in tables().rules]
    return rules


def run(tokens: Iterable[LexedToken], builder: object, state_box: list[int]) -> object:
    """Drive the LALR table over ``tokens`` calling ``builder.<rule>(children)`` on each reduction.

    ``state_box[0]`` always holds the current state, so the lexer can read which keywords the parser
    accepts right now (soft keywords).
    """
    t = tables()
    states = t.states
    rules = _rules_of(builder)
    state_stack = [t.start_state]
    value_stack: list[object] = []
    state_box[0] = t.start_state
    end_state = t.end_state
    last = None
    token = None
    tokens = iter(tokens)
    while True:
        token = next(tokens, None)
        if token is None:
            kind = "$END"
        else:
            last = token
            kind = token.type
        while True:
            state = state_stack[-1]
            if state == end_state and token is None:
                return value_stack[-1]
            action = states[state].get(kind)
            if action is None:
                raise ParseFailure(state, set(states[state]), token if token is not None else _EndToken(last))
            if action[0]:
                if token is None:  # pragma: no cover - the grammar never shifts $END
                    raise ParseFailure(state, set(states[state]), _EndToken(last))
                state_stack.append(action[1])
                value_stack.append(token)
                state_box[0] = action[1]
                break
            callback, origin, size, expand1, inline = rules[action[1]]
            if size:
                children = value_stack[-size:]
                del value_stack[-size:]
                del state_stack[-size:]
            else:
                children = []
            if inline is not None:
                children = _splice(inline, children)
            if expand1 and len(children) == 1:
                value = children[0]
            elif callback is None:   # an inlined rule (or a ?rule, which always has one child)
                value = children if type(children) is _Inline else _Inline(children)
            else:
                value = callback(children)
            goto = states[state_stack[-1]][origin][1]
            state_stack.append(goto)
            value_stack.append(value)
            state_box[0] = goto
