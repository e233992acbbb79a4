"""Follow ``import`` lines: the parsed file plus every library and file it imports, each once, imports first.

Libraries (``import osc.helpers``) are found through the entry-point group
``scenario_execution.osc_libraries`` (see :mod:`coverage_engine.resolve.libraries`); a parsed library is kept
for the life of the process, so resolving many variants parses each library once.
"""

from __future__ import annotations

import os
from pathlib import Path

from coverage_engine.errors import ImportResolutionError, OscError
from coverage_engine.parse import syntax

_parsed_cache: dict[tuple[str, float], syntax.CompilationUnit] = {}

#: Files whose content shapes a parsed unit; a change to any of them invalidates the disk cache.
_PARSER_FILES = ("parse/grammar.lark", "parse/syntax.py", "records.py", "parse/transformer.py",
                 "parse/transformer_expr.py", "parse/strings.py")


def _disk_cache_path(path: Path, stat: os.stat_result) -> Path:
    """Where the parsed form of an imported file is kept between runs (next to the parser tables)."""
    from coverage_engine.parse.cache import cache_file, text_digest

    here = Path(__file__).resolve().parent.parent
    parts = [str(path), str(stat.st_mtime_ns), str(stat.st_size)]
    parts += [str(os.stat(here / name).st_mtime_ns) for name in _PARSER_FILES]
    digest = text_digest("|".join(parts))
    return cache_file("unit" + digest, ".unit")


def _parse_cached(path: Path) -> syntax.CompilationUnit:
    """Parse an imported file once per process, and keep its syntax tree on disk between processes.

    Libraries such as ``osc.types`` are imported by nearly every scenario; reading their pickled tree
    costs a fraction of parsing them again.
    """
    from coverage_engine.parse import cache
    from coverage_engine.parse.parser import parse_file

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
    unit = cache.load(cache_path, syntax.CompilationUnit)
    if unit is None:
        unit = parse_file(resolved)
        cache.store(cache_path, unit)
    _parsed_cache[key] = unit
    return unit


def _library_path(name: str, location: syntax.Location) -> Path:
    from coverage_engine.resolve.libraries import find_library

    try:
        return find_library(name)
    except ImportResolutionError as exc:
        if exc.location is None:
            exc.location = location
        raise


def collect_units(unit: syntax.CompilationUnit, base_dir: Path) -> list[syntax.CompilationUnit]:
    """All units needed by ``unit``, dependencies before dependents, ``unit`` last, each file once."""
    ordered: list[syntax.CompilationUnit] = []
    seen: set[str] = set()

    def visit(current: syntax.CompilationUnit, current_dir: Path, key: str, stack: tuple[str, ...]) -> None:
        if key in seen:
            return
        seen.add(key)
        for imp in current.imports:
            if imp.is_file:
                target = (current_dir / imp.path).resolve()
                if not target.is_file():
                    raise ImportResolutionError(f"cannot import '{imp.path}': no such file ({target})",
                                                imp.location)
            else:
                target = _library_path(imp.path, imp.location).resolve()
            target_key = str(target)
            if target_key in stack:
                continue  # an import cycle: the file is already being read further up
            visit(_parse_cached(target), target.parent, target_key, stack + (target_key,))
        ordered.append(current)

    root_key = str(Path(unit.file).resolve()) if unit.file else "<text>"
    visit(unit, base_dir, root_key, (root_key,))
    return ordered
