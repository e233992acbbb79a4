"""Follow ``import`` lines: the parsed file plus every library and file it imports, each once, imports first.

Libraries (``import osc.helpers``) are found through the entry-point group
``scenario_execution.osc_libraries`` (see :mod:`coverage_engine.resolve.libraries`); a parsed library is kept
for the life of the process, so resolving many variants parses each library once
(:func:`~coverage_engine.parse.parser.parse_file_cached`).
"""

from __future__ import annotations

from pathlib import Path

from coverage_engine.errors import ImportResolutionError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.parse.parser import parse_file_cached


def _library_path(name: str, location: Location) -> Path:
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
            visit(parse_file_cached(target), target.parent, target_key, stack + (target_key,))
        ordered.append(current)

    root_key = str(Path(unit.file).resolve()) if unit.file else "<text>"
    visit(unit, base_dir, root_key, (root_key,))
    return ordered
