"""Which scenario runs go where: names, output directories and ``_output_dir`` overrides.

A file with N scenarios and a parameter file with M YAML documents gives N × M runs, in document
order then file order. Names get ``-<document index>`` only when there is more than one document.
With ``--output-dir``, a single run writes into it directly; several runs each get a subdirectory
named after the run. A document may place a scenario's results with ``_output_dir`` under the
scenario's key: relative paths stay inside ``--output-dir`` (``..`` escaping it is an error),
absolute paths are used as they are.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from coverage_engine.errors import ParameterFileError
from coverage_engine.files.sce import VariantLines
from coverage_engine.location import Location
from coverage_engine.resolve.model import Scenario, ScenarioFile
from coverage_engine.resolve.overrides import OUTPUT_DIR_KEY


class RunOrigin:
    """Where a run comes from, as its ``coverage.json`` tells: the file that was run (as given on the
    command line), the variant's name (a ``.sce`` file's stem) and its assignment (the varied
    parameters and their values, from the ``.sce`` header; empty for an ``.osc``)."""

    def __init__(self, source: str | None = None, variant: str | None = None,
                 assignment: dict[str, object] | None = None, lines: VariantLines | None = None) -> None:
        self.source = source
        self.variant = variant
        self.assignment = dict(assignment or {})
        #: A variant's map from its ``.sce`` lines to those of the ``.osc`` the user wrote.
        self.lines = lines

    def place(self, location: Location) -> str:
        """How a failure message names ``location``: ``file:line:col``, and for a variant the ``.osc``
        line the user wrote before the ``.sce`` line (``gap.osc:11:9 (out/gap3.sce:24:9)``)."""
        return self.lines.place(location) if self.lines is not None else str(location)


class PlannedRun:
    """One scenario run: the resolved scenario, its result name and its output directory."""

    __slots__ = ("scenario", "name", "output_dir")

    def __init__(self, scenario: Scenario, name: str, output_dir: str | None) -> None:
        self.scenario = scenario
        self.name = name
        self.output_dir = output_dir

    def __repr__(self) -> str:
        return f"PlannedRun({self.name!r}, output_dir={self.output_dir!r})"


#: Longest path (bytes) and path component accepted for an ``_output_dir`` (Linux's PATH_MAX and NAME_MAX).
MAX_PATH_BYTES = 4095
MAX_NAME_BYTES = 255


def split_output_dirs(document: Mapping | None,
                      output_root: str | None = None) -> tuple[dict | None, dict[str, str]]:
    """Take ``_output_dir`` out of each scenario's mapping: ``(overrides for the resolver, dirs)``.

    Raises :class:`ParameterFileError` when ``_output_dir`` is not a non-empty string, cannot be a
    folder (a NUL byte, too long, under a file) or escapes the output directory, also through a
    symbolic link inside it (checked on the real path, when ``output_root`` is given). Every
    document is checked before the first run, so a bad folder in the last document runs nothing.
    """
    if document is None:
        return None, {}
    if not isinstance(document, Mapping):
        return document, {}  # the resolver reports what is wrong with it
    overrides: dict = {}
    dirs: dict[str, str] = {}
    for scenario_name, values in document.items():
        if isinstance(values, Mapping) and OUTPUT_DIR_KEY in values:
            values = dict(values)
            target = values.pop(OUTPUT_DIR_KEY)
            if not isinstance(target, str) or not target.strip():
                raise ParameterFileError(
                    f"'{scenario_name}.{OUTPUT_DIR_KEY}': expected a directory path (string), got {target!r}")
            if not os.path.isabs(target):
                normal = os.path.normpath(target)
                if normal == os.pardir or normal.startswith(os.pardir + os.sep):
                    raise ParameterFileError(
                        f"'{scenario_name}.{OUTPUT_DIR_KEY}': '{target}' leaves the output directory; "
                        "use a path inside it, or an absolute path")
            _check_folder(f"{scenario_name}.{OUTPUT_DIR_KEY}", target, output_root)
            dirs[str(scenario_name)] = target
        overrides[scenario_name] = values
    return overrides, dirs


def _check_folder(key: str, target: str, output_root: str | None) -> None:
    """Refuse an ``_output_dir`` that cannot be a folder or that leads out of ``output_root``."""
    if "\0" in target:
        raise ParameterFileError(f"'{key}': the path holds a NUL character, which no file system allows")
    encoded = os.fsencode(target)
    if len(encoded) > MAX_PATH_BYTES or any(len(part) > MAX_NAME_BYTES for part in encoded.split(b"/")):
        raise ParameterFileError(f"'{key}': the path is too long ({len(encoded)} bytes; at most "
                                 f"{MAX_PATH_BYTES}, and {MAX_NAME_BYTES} per folder name)")
    if output_root is None and not os.path.isabs(target):
        return
    root = os.path.abspath(output_root) if output_root is not None else ""
    folder = os.path.normpath(target if os.path.isabs(target) else os.path.join(root, target))
    if not os.path.isabs(target):
        real = Path(folder).resolve()
        if not real.is_relative_to(Path(root).resolve()):
            raise ParameterFileError(
                f"'{key}': '{target}' leads out of the output directory through a symbolic link "
                f"(to {real}); use a path inside it, or an absolute path")
    existing = folder
    while not os.path.lexists(existing):
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        raise ParameterFileError(f"'{key}': '{target}' cannot be a folder: {existing} is a file")


def plan_runs(loaded: Sequence[tuple[ScenarioFile, Mapping[str, str]]], output_root: str | None) -> list[PlannedRun]:
    """The runs for each loaded document (its resolved file and its ``_output_dir`` values)."""
    suffixed = len(loaded) > 1
    count = sum(len(scenario_file.scenarios) for scenario_file, _ in loaded)
    runs = []
    for index, (scenario_file, dirs) in enumerate(loaded):
        for scenario in scenario_file.scenarios:
            name = f"{scenario.name}-{index}" if suffixed else scenario.name
            runs.append(PlannedRun(scenario, name,
                                   output_dir_for(output_root, dirs.get(scenario.name), name, count > 1)))
    return runs


def output_dir_for(root: str | None, override: str | None, name: str, several: bool) -> str | None:
    """Absolute output directory of one run (None without ``--output-dir`` and no absolute override)."""
    if override is not None and os.path.isabs(override):
        return os.path.normpath(override)
    if root is None:
        return None
    root = os.path.abspath(root)
    if override is not None:
        return os.path.normpath(os.path.join(root, override))
    return os.path.join(root, name) if several else root
