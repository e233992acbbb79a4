"""Entry point of the front end: a scenario file (``.osc`` or ``.sce``) in, a resolved model out.

This is the only function the executor and the commands need: ``load_scenario_file``. It reads the
file, parses it (``coverage_engine.parse.parser``), and resolves it with optional parameter overrides
(``coverage_engine.resolve.resolver``). It never imports the runtime.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

from coverage_engine.errors import OscError
from coverage_engine.parse.syntax import CompilationUnit
from coverage_engine.resolve.model import ScenarioFile
from coverage_engine.suffixes import SCE_SUFFIX, SCENARIO_SUFFIXES


def load_scenario_file(path: str | Path, overrides: Mapping[str, object] | None = None) -> ScenarioFile:
    """Parse and resolve ``path``; ``overrides`` is one YAML document of scenario parameter values.

    Raises :class:`~coverage_engine.errors.OscError` (with a location) for anything wrong in the input.
    """
    from coverage_engine.parse.parser import parse_file, parse_text
    from coverage_engine.resolve.resolver import resolve

    path = Path(path)
    if path.suffix not in SCENARIO_SUFFIXES:
        raise OscError(f"{path}: not a scenario file (expected .osc or .sce)")
    if not path.is_file():
        raise OscError(f"{path}: no such file")
    if path.suffix == SCE_SUFFIX:
        from coverage_engine.files.sce import read_sce

        document = read_sce(path)
        unit = parse_text(document.text, str(path))
        base_dir = Path(document.source_dir)
        if document.parameters:
            from coverage_engine.resolve.overrides import scenario_overrides

            # the runner's _output_dir placed the document's run; a variant's results go where it is run
            overrides = merge_overrides(scenario_overrides(dict(document.parameters)) or {}, overrides)
    else:
        unit = _parsed(path, parse_file)
        base_dir = path.parent
    return resolve(unit, base_dir=base_dir, overrides=overrides)


#: The last ``.osc`` parsed, by path and identity (size, modification time): the same file is loaded once
#: per parameter document, and its syntax tree does not depend on the document.
_last_parsed: tuple[tuple[str, int, int, int], CompilationUnit] | None = None


def _parsed(path: Path, parse_file: Callable[[Path], CompilationUnit]) -> CompilationUnit:
    """The syntax tree of ``path``, parsed again only when the file changed since the last call."""
    global _last_parsed
    stat = path.stat()
    key = (str(path.resolve()), stat.st_size, stat.st_mtime_ns, stat.st_ino)
    if _last_parsed is not None and _last_parsed[0] == key:
        return _last_parsed[1]
    unit = parse_file(path)
    _last_parsed = (key, unit)
    return unit


def merge_overrides(base: Mapping[str, object], top: Mapping[str, object] | None) -> dict[str, object]:
    """Parameter documents combined: ``top`` (the command line's) wins, scenario by scenario."""
    merged: dict[str, object] = {name: dict(values) if isinstance(values, Mapping) else values
                                 for name, values in base.items()}
    for name, values in (top or {}).items():
        current = merged.get(name)
        if isinstance(current, dict) and isinstance(values, Mapping):
            current.update(values)
        else:
            merged[name] = values
    return merged
