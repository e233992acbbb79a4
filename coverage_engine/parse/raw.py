"""One parse without messages: our lexer → the indentation post-lexer → the LALR driver → the syntax builder.

A failure of the grammar comes out as the driver's :class:`~coverage_engine.parse.lalr.ParseFailure`;
:mod:`~coverage_engine.parse.parser` turns it into our error, and
:mod:`~coverage_engine.parse.syntax_errors` parses its table of labelled bad snippets with this too.
The parts are shared by the process, so callers hold :data:`LOCK` around a parse.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING, cast

from coverage_engine.parse.indenter import OscIndenter
from coverage_engine.parse.lalr import run
from coverage_engine.parse.lexer import OscLexer
from coverage_engine.parse.syntax import CompilationUnit
from coverage_engine.parse.tables import tables

if TYPE_CHECKING:   # imported on first use: it loads every syntax node class
    from coverage_engine.parse.transformer import SyntaxBuilder

#: Held while the shared lexer, post-lexer and builder are in use (re-entrant: error hints parse again).
LOCK = threading.RLock()
_PARTS: tuple[OscLexer, OscIndenter, SyntaxBuilder] | None = None


def _parts() -> tuple[OscLexer, OscIndenter, SyntaxBuilder]:
    """The per-process lexer, post-lexer and builder (created on first use)."""
    global _PARTS
    if _PARTS is None:
        from coverage_engine.parse.transformer import SyntaxBuilder

        _PARTS = (OscLexer(tables()), OscIndenter(), SyntaxBuilder())
    return _PARTS


def raw_parse(text: str, file: str = "<snippet>") -> CompilationUnit:
    """Parse ``text``; failures come out as :class:`~coverage_engine.parse.lalr.ParseFailure`."""
    lexer, indenter, builder = _parts()
    if not text.endswith(("\n", "\r")):
        text += "\n"  # every statement ends with a newline token, also the last one
    indenter.file, indenter.text = file, text
    builder.reset(file, text)
    state_box = [0]
    return cast(CompilationUnit, run(indenter.process(lexer.lex(text, state_box)), builder, state_box))
