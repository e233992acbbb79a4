"""The LALR tables of ``grammar.lark``, built by lark once and cached, and a small driver that runs them.

Why not call ``Lark.parse``: importing lark and loading its cached parser costs ~45 ms, more than
half of the 80 ms budget of a whole ``scenario_execution -n`` run, and its generic parse loop is
the larger part of the parse time. lark stays the grammar compiler: when the grammar (or lark)
changes, :func:`tables` asks lark for the LALR table and stores the few plain facts the driver
needs -- per state the action of each terminal, per rule its callback name, length and how lark
would shape its children (``_rule`` inlined, ``?rule`` with one child replaced by it, every token
kept) -- in a pickle beside lark's own cache. A parse failure is a :class:`ParseFailure` carrying
the parser state, which :mod:`coverage_engine.parse.syntax_errors` turns into our error.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from coverage_engine.parse.cache import cache_file, load, store, text_digest

GRAMMAR_PATH = Path(__file__).resolve().parent / "grammar.lark"
FORMAT = 2


@dataclass
class Tables:
    """Everything the lexer and driver need: states, rules, keyword and punctuation maps."""

    states: dict[int, dict[str, tuple[bool, int]]]  # state -> terminal -> (shift?, state or rule)
    rules: list[tuple[str, str, int, bool, tuple[bool, ...] | None]]  # callback, origin, length,
    #                                                                    expand1, inline mask
    start_state: int
    end_state: int
    keywords: dict[str, str]  # "keep" -> "KEEP"
    punctuation: dict[str, str]  # "(" -> "LPAR"
    terminal_words: dict[str, str]  # terminal name -> its literal text, for messages


class ParseFailure(Exception):
    """Raised by the lexer or driver: ``token`` (or a bad character at ``pos``) in parser ``state``."""

    def __init__(self, state: int, expected: set[str], token=None, pos: int = 0, line: int = 1,
                 column: int = 1) -> None:
        super().__init__("parse failure")
        self.state, self.expected, self.token = state, expected, token
        self.pos, self.line, self.column = pos, line, column


def _build(grammar_text: str) -> Tables:
    """Compile the grammar with lark and extract the tables (slow; runs once per grammar change)."""
    from lark import Lark

    from coverage_engine.parse.lexer import NAME_RE

    lark_parser = Lark(grammar_text, parser="lalr", keep_all_tokens=True, maybe_placeholders=False)
    table = lark_parser.parser.parser._parse_table
    rule_index: dict[object, int] = {}
    rules: list[tuple[str, str, int, bool, tuple[bool, ...] | None]] = []
    states: dict[int, dict[str, tuple[bool, int]]] = {}
    for state, actions in table.states.items():
        row: dict[str, tuple[bool, int]] = {}
        for terminal, (action, arg) in actions.items():
            if action.name == "Shift":
                row[str(terminal)] = (True, int(arg))
                continue
            if arg not in rule_index:
                rule_index[arg] = len(rules)
                inline = tuple((not sym.is_term) and sym.name.startswith("_") for sym in arg.expansion)
                name = str(arg.alias or arg.origin.name)
                expand1 = bool(arg.options.expand1) and not arg.alias
                rules.append((name, str(arg.origin.name), len(arg.expansion), expand1,
                              inline if any(inline) else None))
            row[str(terminal)] = (False, rule_index[arg])
        states[int(state)] = row
    keywords, punctuation, words = {}, {}, {}
    for terminal in lark_parser.terminals:
        if terminal.pattern.type != "str":
            continue
        name, value = str(terminal.name), str(terminal.pattern.value)
        words[name] = value
        if NAME_RE.fullmatch(value):
            keywords[value] = name
        else:
            punctuation[value] = name
    return Tables(states, rules, int(table.start_states["start"]), int(table.end_states["start"]),
                  keywords, punctuation, words)


_TABLES: Tables | None = None


def tables() -> Tables:
    """The tables for the current grammar: from the pickle cache, else built with lark and cached."""
    global _TABLES
    if _TABLES is not None:
        return _TABLES
    grammar_text = GRAMMAR_PATH.read_text(encoding="utf-8")
    cache = cache_file(text_digest(f"{FORMAT}\n{grammar_text}"))
    loaded = load(cache, Tables)
    if loaded is not None:
        _TABLES = loaded
        return loaded
    built = _build(grammar_text)
    store(cache, built)
    _TABLES = built
    return built


class _EndToken:
    """The end-of-input token, placed right after the last real token."""

    type = "$END"

    def __init__(self, last) -> None:
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


def run(tokens, builder, state_box: list[int]) -> object:
    """Drive the LALR table over ``tokens`` calling ``builder.<rule>(children)`` on each reduction.

    ``state_box[0]`` always holds the current state, so the lexer can read which keywords the parser
    accepts right now (soft keywords).
    """
    t = tables()
    states = t.states
    # per rule: callback (None for inlined rules), goto symbol, length, expand1, inline mask
    rules = _bound_rules.get(id(builder))
    if rules is None:
        rules = _bound_rules[id(builder)] = [
            (None if name[0] == "_" else getattr(builder, name, None), origin, size, expand1, inline)
            for name, origin, size, expand1, inline in t.rules]
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
                spliced: list[object] = []
                for flag, child in zip(inline, children, strict=True):
                    if flag and type(child) is _Inline:
                        spliced.extend(child)
                    else:
                        spliced.append(child)
                children = spliced
            if expand1 and len(children) == 1:
                value = children[0]
            elif callback is None:
                value = _Inline(children)  # an inlined rule (or a ?rule, which always has one child)
            else:
                value = callback(children)
            goto = states[state_stack[-1]][origin][1]
            state_stack.append(goto)
            value_stack.append(value)
            state_box[0] = goto
