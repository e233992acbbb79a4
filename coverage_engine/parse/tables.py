"""The LALR tables of ``grammar.lark``: compiled by lark once, kept in a cache, read by the lexer and driver.

Why not call ``Lark.parse``: importing lark and loading its cached parser costs ~45 ms, more than
half of the 80 ms budget of a whole ``scenario_execution -n`` run, and its generic parse loop is
the larger part of the parse time. lark stays the grammar compiler: when the grammar (or lark)
changes, :func:`tables` asks lark for the LALR table and stores the few plain facts our lexer
(:mod:`~coverage_engine.parse.lexer`) and driver (:mod:`~coverage_engine.parse.lalr`) need -- per
state the action of each terminal, per rule its callback name, length and how lark would shape its
children (``_rule`` inlined, ``?rule`` with one child replaced by it, every token kept) -- in a
pickle beside lark's own cache.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from coverage_engine.parse.cache import cache_file, files_digest, load, store, text_digest

GRAMMAR_PATH = Path(__file__).resolve().parent / "grammar.lark"
FORMAT = 2

#: A name of the language; a literal terminal that matches it is a (soft) keyword, any other is punctuation.
NAME_RE = re.compile(r"[^\W\d]\w*")


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


def _build(grammar_text: str) -> Tables:
    """Compile the grammar with lark and extract the tables (slow; runs once per grammar change)."""
    from lark import Lark

    lark_parser = Lark(grammar_text, parser="lalr", keep_all_tokens=True, maybe_placeholders=False)
    # lark has no public accessor for its LALR table; this attribute path is stable across the lark
    # releases pyproject.toml admits (tested in CI with the newest of them). Another lark fails here,
    # with a message, rather than anywhere later.
    try:
        table = lark_parser.parser.parser._parse_table
        table.states, table.start_states, table.end_states  # noqa: B018 - the parts read below
    except AttributeError as exc:
        import lark

        raise RuntimeError(f"lark {getattr(lark, '__version__', '?')} is not supported: its LALR table is not where "
                           "lark 1.1.9 to 1.3 keep it; install a release pyproject.toml admits") from exc
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


def _lark_version() -> str:
    """Which lark is installed, without importing it (~45 ms) or importlib.metadata (~13 ms): the
    location, size and modification time of its ``__init__.py``, which names its version."""
    from importlib.util import find_spec

    spec = find_spec("lark")
    if spec is None or not spec.origin:
        return "none"
    return files_digest(Path(spec.origin).parent, ("__init__.py", "parsers/lalr_analysis.py")) + spec.origin


def tables() -> Tables:
    """The tables for the current grammar: from the pickle cache, else built with lark and cached."""
    global _TABLES
    if _TABLES is not None:
        return _TABLES
    grammar_text = GRAMMAR_PATH.read_text(encoding="utf-8")
    # The tables' shape is decided here and read by the lexer, the indenter and the LALR driver: a
    # change to any of them (or another lark) must not reuse tables built for the old code.
    sources = files_digest(GRAMMAR_PATH.parent, ("tables.py", "lexer.py", "indenter.py", "lalr.py"))
    cache = cache_file(text_digest(f"{FORMAT}\n{_lark_version()}\n{sources}\n{grammar_text}"))
    loaded = load(cache, Tables)
    if loaded is not None:
        _TABLES = loaded
        return loaded
    built = _build(grammar_text)
    store(cache, built)
    _TABLES = built
    return built
