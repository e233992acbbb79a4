"""Parse ``.osc`` text into a :class:`~coverage_engine.syntax.CompilationUnit`.

The grammar (``grammar.lark``) is loaded once per process, from lark's on-disk cache after the first
run, as an LALR parser with a contextual lexer and the indentation post-lexer. One Transformer
(:mod:`coverage_engine.transformer`) builds the syntax nodes. Every failure the text can cause comes
out as an :class:`~coverage_engine.errors.OscError` with a location -- never as a lark exception.
"""

from __future__ import annotations

from pathlib import Path

from lark import Lark
from lark.exceptions import UnexpectedInput, VisitError

from coverage_engine.errors import OscError, OscSyntaxError
from coverage_engine.indenter import OscIndenter
from coverage_engine.syntax import CompilationUnit, Location

_LARK: Lark | None = None
_INDENTER = OscIndenter()


def grammar() -> Lark:
    """The process-wide LALR parser (built or loaded from lark's cache on first use)."""
    global _LARK
    if _LARK is None:
        _LARK = Lark.open_from_package(
            "coverage_engine", "grammar.lark", ("",),
            parser="lalr", lexer="contextual", postlex=_INDENTER,
            propagate_positions=True, maybe_placeholders=True, cache=True,
        )
    return _LARK


def _raw_parse(text: str):
    """Parse ``text`` to a lark tree (no syntax nodes): used for parsing and by the error-hint table."""
    if not text.endswith(("\n", "\r")):
        text += "\n"  # every statement ends with a newline token, also the last one
    return grammar().parse(text)


def parse_text(text: str, file: str) -> CompilationUnit:
    """Parse the ``.osc`` source ``text``; ``file`` is the name every location will carry."""
    from coverage_engine.transformer import SyntaxBuilder

    if text.startswith("\ufeff"):
        text = " " + text[1:]  # keep offsets; a BOM is just blank space to the grammar
    _INDENTER.file, _INDENTER.text = file, text
    try:
        tree = _raw_parse(text)
    except UnexpectedInput as exc:
        from coverage_engine.syntax_errors import syntax_error_from_lark

        raise syntax_error_from_lark(exc, file, text) from None
    except RecursionError:
        raise OscSyntaxError("the text is nested too deeply to parse", Location(file, 1, 1)) from None
    try:
        return SyntaxBuilder(file, text).transform(tree)
    except VisitError as exc:
        orig = exc.orig_exc
        if isinstance(orig, OscError):
            raise orig from None
        meta = getattr(exc.obj, "meta", None)
        line, column = getattr(meta, "line", 1), getattr(meta, "column", 1)
        lines = text.splitlines()
        raise OscSyntaxError(
            f"cannot read this {exc.rule or 'construct'}: {orig}",
            Location(file, line, column), lines[line - 1] if 0 < line <= len(lines) else None,
        ) from None
    except RecursionError:
        raise OscSyntaxError("the text is nested too deeply to parse", Location(file, 1, 1)) from None


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
