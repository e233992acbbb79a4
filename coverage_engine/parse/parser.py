"""Parse ``.osc`` text into a :class:`~coverage_engine.parse.syntax.CompilationUnit`, with our errors.

``grammar.lark`` is compiled by lark into LALR tables once and cached (:mod:`~coverage_engine.parse.tables`);
a parse is our lexer (:mod:`~coverage_engine.parse.lexer`) → the indentation post-lexer
(:mod:`~coverage_engine.parse.indenter`) → the table driver (:mod:`~coverage_engine.parse.lalr`), which
calls the one syntax builder (:mod:`~coverage_engine.parse.transformer`) on every reduction, so no
intermediate tree is built (:mod:`~coverage_engine.parse.raw`). Every failure the text can cause comes
out here as an :class:`~coverage_engine.errors.OscError` with a location. Imported files (libraries) are
parsed through :func:`parse_file_cached`, which keeps their syntax trees between runs.
"""

from __future__ import annotations

import os
from pathlib import Path

from coverage_engine.errors import OscError, OscSyntaxError
from coverage_engine.limits import MAX_SOURCE_BYTES, mib
from coverage_engine.location import Location
from coverage_engine.parse import cache
from coverage_engine.parse.lalr import ParseFailure
from coverage_engine.parse.lexer import AdjacentLiterals
from coverage_engine.parse.raw import LOCK, raw_parse
from coverage_engine.parse.syntax import CompilationUnit


def parse_text(text: str, file: str) -> CompilationUnit:
    """Parse the ``.osc`` source ``text``; ``file`` is the name every location will carry."""
    if text.startswith("\ufeff"):
        text = " " + text[1:]  # keep offsets; a byte-order mark is just blank space to the grammar
    with LOCK:
        try:
            return raw_parse(text, file)
        except OscError:
            raise
        except AdjacentLiterals as exc:
            lines = text.splitlines()
            raise OscSyntaxError(exc.message, Location(file, exc.line, exc.column),
                                 source_line=lines[exc.line - 1] if 0 < exc.line <= len(lines) else None) from None
        except ParseFailure as exc:
            from coverage_engine.parse.syntax_errors import syntax_error

            raise syntax_error(exc, file, text) from None
        except RecursionError:
            raise OscSyntaxError("the text is nested too deeply to parse", Location(file, 1, 1)) from None
        except (ValueError, OverflowError) as exc:  # e.g. an integer literal of 5000 digits
            raise OscSyntaxError(f"cannot read a literal: {exc}", Location(file, 1, 1)) from None


def parse_file(path: str | Path) -> CompilationUnit:
    """Read ``path`` as UTF-8 and parse it; an unreadable file, or one larger than
    :data:`MAX_SOURCE_BYTES`, is an :class:`OscError` naming it."""
    path = Path(path)
    try:
        with open(path, encoding="utf-8", newline="") as handle:
            size = os.fstat(handle.fileno()).st_size
            if size > MAX_SOURCE_BYTES:
                raise OscError(f"{path}: {size:,} bytes, larger than the limit of "
                               f"{mib(MAX_SOURCE_BYTES)} for a scenario file")
            text = handle.read(MAX_SOURCE_BYTES + 1)
    except UnicodeDecodeError as exc:
        raise OscError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise OscError(f"{path}: cannot read file: {exc.strerror or exc}") from None
    return parse_text(text, str(path))


_parsed_cache: dict[tuple[str, float], CompilationUnit] = {}

#: Files whose content shapes a parsed unit (relative to ``coverage_engine/``); a change to any of them
#: invalidates the disk cache.
_PARSER_FILES = ("parse/grammar.lark", "parse/lexer.py", "parse/indenter.py", "parse/lalr.py", "parse/tables.py",
                 "parse/parser.py", "parse/syntax.py", "parse/transformer.py", "parse/transformer_expr.py",
                 "parse/strings.py", "parse/parts.py", "location.py", "records.py")


def _disk_cache_path(path: Path, stat: os.stat_result) -> Path | None:
    """Where the parsed form of an imported file is kept between runs (next to the parser tables)."""
    package = Path(__file__).resolve().parent.parent
    parts = [str(path), str(stat.st_mtime_ns), str(stat.st_size), cache.files_digest(package, _PARSER_FILES)]
    return cache.cache_file("unit" + cache.text_digest("|".join(parts)), ".unit")


def parse_file_cached(path: Path) -> CompilationUnit:
    """Parse an imported file once per process, and keep its syntax tree on disk between processes.

    Libraries such as ``osc.types`` are imported by nearly every scenario; reading their pickled tree
    costs a fraction of parsing them again.
    """
    resolved = path.resolve()
    try:
        stat = os.stat(resolved)
    except OSError as exc:
        raise OscError(f"cannot read {path}: {exc.strerror}") from exc
    key = (str(resolved), stat.st_mtime)
    unit = _parsed_cache.get(key)
    if unit is not None:
        return unit
    cache_path = _disk_cache_path(resolved, stat)
    unit = cache.load(cache_path, CompilationUnit)
    if unit is None:
        unit = parse_file(resolved)
        cache.store(cache_path, unit)
    _parsed_cache[key] = unit
    return unit
