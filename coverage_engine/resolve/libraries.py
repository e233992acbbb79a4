"""Find the ``.osc`` file of ``import osc.<name>`` through the entry-point group ``scenario_execution.osc_libraries``.

As in the reference: the entry point's *name* is the library name (``helpers`` for ``import
osc.helpers``) and it loads a function returning ``(package, relative path)``; the file is
``<package dir>/lib_osc/<relative path>``. We also accept ``<package dir>/<relative path>``, which
is where our own libraries live (``coverage_engine/osc/``). Our four libraries are answered without
scanning installed metadata (that scan costs milliseconds of every run); any other name is looked
up once per process.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

from coverage_engine.errors import ImportResolutionError
from coverage_engine.suffixes import OSC_SUFFIX

GROUP = "scenario_execution.osc_libraries"
OWN_DIR = Path(__file__).resolve().parent.parent / "osc"
OWN_LIBRARIES = ("types", "helpers", "standard", "robotics")


def get_types_library() -> tuple[str, str]:
    """Entry point of ``osc.types``: SI physical types and units."""
    return "coverage_engine", "osc/types.osc"


def get_helpers_library() -> tuple[str, str]:
    """Entry point of ``osc.helpers``: log, run_process, compare, … and the common modifiers."""
    return "coverage_engine", "osc/helpers.osc"


def get_standard_library() -> tuple[str, str]:
    """Entry point of ``osc.standard``: positions, orientations, poses, velocities."""
    return "coverage_engine", "osc/standard.osc"


def get_robotics_library() -> tuple[str, str]:
    """Entry point of ``osc.robotics``: the ``robot`` actor."""
    return "coverage_engine", "osc/robotics.osc"


def library_name(import_name: str) -> str:
    """``osc.helpers`` -> ``helpers``; anything not under ``osc.`` is an :class:`ImportResolutionError`."""
    parts = import_name.split(".")
    if len(parts) < 2 or parts[0] != "osc" or not all(parts):
        raise ImportResolutionError(
            f"cannot import '{import_name}': library imports are written osc.<library-name>")
    return ".".join(parts[1:])


@cache
def _registered() -> dict[str, list]:
    """Entry points of the group by name (a name may be registered by more than one package)."""
    from importlib.metadata import entry_points

    found: dict[str, list] = {}
    for ep in entry_points(group=GROUP):
        found.setdefault(ep.name, []).append(ep)
    return found


def _file_of(package: str, relative: str) -> Path | None:
    from importlib.resources import files

    base = Path(str(files(package)))
    for candidate in (base / "lib_osc" / relative, base / relative):
        if candidate.is_file():
            return candidate
    return None


def find_library(import_name: str) -> Path:
    """The ``.osc`` file that ``import <import_name>`` (e.g. ``osc.helpers``) reads."""
    name = library_name(import_name)
    if name in OWN_LIBRARIES:
        own = OWN_DIR / f"{name}{OSC_SUFFIX}"
        if own.is_file():
            return own
    candidates = _registered().get(name, [])
    if not candidates:
        raise ImportResolutionError(f"no import library '{name}' found (import {import_name})")
    paths: list[Path] = []
    for ep in candidates:
        try:
            package, relative = ep.load()()
            path = _file_of(package, relative)
        except Exception as exc:  # noqa: BLE001 - a broken plugin is the user's error to see
            raise ImportResolutionError(
                f"library '{name}' ({ep.value}) cannot be loaded: {exc}") from None
        if path is None:
            raise ImportResolutionError(
                f"library '{name}' ({ep.value}) names {relative!r} in package {package!r}, "
                "which does not exist")
        if path.resolve() not in [p.resolve() for p in paths]:
            paths.append(path)
    if len(paths) > 1:
        raise ImportResolutionError(
            f"more than one import library '{name}' found: " + ", ".join(str(p) for p in paths))
    return paths[0]
