"""Parse ``.osc`` text into a :class:`~coverage_engine.parse.syntax.CompilationUnit`.

``grammar.lark`` is compiled by lark into LALR tables once and cached (:mod:`coverage_engine.parse.lalr`);
a parse is our lexer (:mod:`coverage_engine.parse.lexer`) → the indentation post-lexer
(:mod:`coverage_engine.parse.indenter`) → the table driver, which calls the one syntax builder
(:mod:`coverage_engine.parse.transformer`) on every reduction, so no intermediate tree is built. Every
failure the text can cause comes out as an :class:`~coverage_engine.errors.OscError` with a location.
"""

from __future__ import annotations

import threading
from pathlib import Path

from coverage_engine.errors import OscError, OscSyntaxError
from coverage_engine.parse.indenter import OscIndenter
from coverage_engine.parse.lalr import ParseFailure, run, tables
from coverage_engine.parse.lexer import OscLexer
from coverage_engine.parse.syntax import CompilationUnit, Location

_LOCK = threading.RLock()
_PARTS: tuple | None = None


def _parts():
    """The per-process lexer, post-lexer and builder (created on first use)."""
    global _PARTS
    if _PARTS is None:
        from coverage_engine.parse.transformer import SyntaxBuilder

        _PARTS = (OscLexer(tables()), OscIndenter(), SyntaxBuilder())
    return _PARTS


def raw_parse(text: str, file: str = "<snippet>"):
    """Parse ``text``; failures come out as :class:`ParseFailure` (used by the error-hint table too)."""
    lexer, indenter, builder = _parts()
    if not text.endswith(("\n", "\r")):
        text += "\n"  # every statement ends with a newline token, also the last one
    indenter.file, indenter.text = file, text
    builder.reset(file, text)
    state_box = [0]
    return run(indenter.process(lexer.lex(text, state_box)), builder, state_box)


def parse_text(text: str, file: str) -> CompilationUnit:
    """Parse the ``.osc`` source ``text``; ``file`` is the name every location will carry."""
    if text.startswith("\ufeff"):
        text = " " + text[1:]  # keep offsets; a byte-order mark is just blank space to the grammar
    with _LOCK:
        try:
            return raw_parse(text, file)
        except OscError:
            raise
        except ParseFailure as exc:
            from coverage_engine.parse.syntax_errors import syntax_error

            raise syntax_error(exc, file, text) from None
        except RecursionError:
            raise OscSyntaxError("the text is nested too deeply to parse", Location(file, 1, 1)) from None
        except (ValueError, OverflowError) as exc:  # e.g. an integer literal of 5000 digits
            raise OscSyntaxError(f"cannot read a literal: {exc}", Location(file, 1, 1)) from None


def parse_file(path: str | Path) -> CompilationUnit:
    """Read ``path`` as UTF-8 and parse it; an unreadable file is an :class:`OscError` naming it."""
    path = Path(path)
    try:
        with open(path, encoding="utf-8", newline="") as handle:
            text = handle.read()
    except UnicodeDecodeError as exc:
        raise OscError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise OscError(f"{path}: cannot read file: {exc.strerror or exc}") from None
    return parse_text(text, str(path))
