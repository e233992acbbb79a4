"""The ``.sce`` format: one concrete variant of an ``.osc`` scenario, as small human-readable YAML.

``scenario_variation`` writes one ``.sce`` per combination of varied values; ``scenario_execution``
loads it exactly like the ``.osc`` it came from (see :mod:`coverage_engine.files.loader`). A file looks like::

    # scenario_variation .sce, format 2: variant 1 of example.osc
    # example_variation.log.msg = "bar"
    format_version: 2
    source: "example.osc"
    source_sha256: "9f86d08…"
    source_dir: ".."
    scenario: "example_variation"
    index: 1
    assignment:
      "example_variation.log.msg": "bar"
    model: |2
      import osc.helpers
      scenario example_variation:
      ...
    # end of .sce

Why this shape:

* ``model`` is the concrete ``.osc`` text (each ``in [...]`` replaced by ``== value``), so imports such as
  ``import osc.helpers`` stay import lines: libraries are referenced by name, never copied, and a
  ``.sce`` stays a few hundred bytes.
* ``source_dir`` is where relative imports and external Python modules are found. It is written
  relative to the ``.sce``'s own folder when possible, so a checkout can move (or be mounted at another
  path on a batch host) and its ``.sce`` files still load; :func:`read_sce` returns it absolute.
* The model's lines are given back with as many blank lines in front as the block starts below the
  top of the file, so an error in a ``.sce`` names the ``.sce`` line the user sees.
* The last line, ``# end of .sce``, is what tells a complete file from one cut short (format 2; files
  of format 1 have no such line and are still read). ``source_sha256`` is provenance only (which
  ``.osc`` text the variant came from); loading never compares it: the model is in the file.
* Everything written is deterministic (no time stamps): the SHA-256 of the text is the variant's
  identity in the store, and regenerating the same input gives byte-identical files.

The writer is :mod:`coverage_engine.files.sce_writer`; files in its shape are read without YAML
(:mod:`coverage_engine.files.sce_plain`).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from coverage_engine.domains import InputDomain, header_domains
from coverage_engine.errors import SceFormatError
from coverage_engine.files.sce_plain import load_plain
from coverage_engine.limits import MAX_YAML_BYTES, mib
from coverage_engine.location import Location

#: The format version this release writes.
SCE_FORMAT_VERSION = 2
#: The versions this release reads. Version 2 is version 1 plus the closing :data:`SCE_END` line.
SCE_READABLE_VERSIONS = (1, 2)

#: First line of every file we write (also how an earlier generation's files are recognised).
SCE_MAGIC = "# scenario_variation .sce"
#: Last line of every file of version 2: a file without it was cut short (disk full, killed copy).
SCE_END = "# end of .sce"

_DECLARED_VERSION = re.compile(re.escape(SCE_MAGIC) + r", format (\d+)")

_REQUIRED = {
    "format_version": int,
    "source": str,
    "source_sha256": str,
    "source_dir": str,
    "scenario": str,
    "assignment": dict,
    "model": str,
}

#: Keys a ``.sce`` file may have besides the required ones.
_OPTIONAL = ("index", "parameters")

@dataclass(frozen=True)
class SceDocument:
    """A loaded ``.sce`` file.

    ``text`` is the concrete ``.osc`` text to parse (padded so its line numbers are those of the
    ``.sce``); ``source_dir`` the absolute folder of the original ``.osc``; ``assignment`` maps each
    varied parameter (``scenario.path``) to its value; ``parameters`` is the scenario parameter
    document this variant was made with (``{scenario: {param: value}}``), or None.
    """

    text: str
    source_dir: str
    scenario: str
    assignment: dict[str, object]
    format_version: int
    source: str
    source_sha256: str
    index: int | None = None
    parameters: dict[str, object] | None = None
    path: str = ""
    extra: dict[str, object] = field(default_factory=dict)
    #: What the variation declared per varied parameter (the header's ``# domain`` lines).
    domains: tuple[InputDomain, ...] = ()
    #: Lines of the ``.sce`` above its model's first line (a model line's ``.sce`` line minus its own).
    model_offset: int = 0


@dataclass(frozen=True)
class VariantLines:
    """Which line of the ``.osc`` a line of a variant's ``.sce`` model stands for.

    The model keeps the line numbers of the ``.osc`` it was generated from (see
    :mod:`coverage_engine.variation.template`), shifted down by the header above it; so a failure in a
    variant can name both the line the user wrote and the line of the file that ran.
    """

    sce_file: str
    source_file: str
    offset: int

    def place(self, location: Location) -> str:
        """``gap.osc:11:9 (out/gap3.sce:24:9)`` for a location in the model, else the location alone."""
        line = location.line - self.offset
        if location.file != self.sce_file or location.is_whole_file or line < 1:
            return str(location)
        return f"{self.source_file}:{line}:{location.column} ({location})"


def variant_lines(document: SceDocument) -> VariantLines:
    """The line map of a loaded ``.sce``: its source shown relative to the working folder when the
    ``.sce`` path is relative (as the user typed it), absolute otherwise."""
    source = os.path.join(document.source_dir, document.source)
    if not os.path.isabs(document.path):
        source = os.path.relpath(source)
    return VariantLines(document.path, source, document.model_offset)


def is_sce_text(head: str) -> bool:
    """Whether a file starting with ``head`` was written by ``scenario_variation``."""
    return head.startswith(SCE_MAGIC)


def _load_yaml(text: str, path: str) -> Any:
    import yaml

    from coverage_engine.yaml_bounds import (
        SAFE_LOADER,
        DuplicateKeyError,
        YamlLimitError,
        load_bounded,
        with_unique_keys,
    )

    loader = with_unique_keys(SAFE_LOADER)
    try:
        return load_bounded(text, loader)
    except DuplicateKeyError as exc:
        raise SceFormatError(f"malformed .sce file: {exc}", Location(path, exc.line, exc.column)) from None
    except YamlLimitError as exc:
        raise SceFormatError(f"not a usable .sce file: {exc}", Location.at(path, exc.line, exc.column)) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        location = Location(path, mark.line + 1, mark.column + 1) if mark is not None else None
        raise SceFormatError(f"not a valid .sce file: {exc.problem or exc}", location) from exc
    except yaml.YAMLError as exc:
        position = getattr(exc, "position", None)       # a character YAML does not accept (ReaderError)
        if isinstance(position, int):
            line = text.count("\n", 0, position) + 1
            column = position - (text.rfind("\n", 0, position) + 1) + 1
            character = getattr(exc, "character", "")
            code = ord(character) if isinstance(character, str) and len(character) == 1 else character
            shown = f"{code:#x}" if isinstance(code, int) else "?"
            raise SceFormatError(f"not a valid .sce file: character {shown} is not allowed in YAML",
                                 Location(path, line, column)) from None
        raise SceFormatError(f"not a valid .sce file: {exc}", Location.whole_file(path)) from exc


def _model_first_line(text: str) -> int:
    """1-based line of the ``.sce`` on which the model's first line stands (0 when not a block)."""
    for number, line in enumerate(text.split("\n"), start=1):
        if line.startswith("model:"):
            return number + 1 if line.rstrip().startswith("model: |") else 0
    return 0


def _truncated(text: str, path: str) -> SceFormatError:
    lines = text.rstrip("\n").count("\n") + 1
    return SceFormatError(f"truncated .sce file: it ends at line {lines} without the closing '{SCE_END}' line "
                          "(the file was cut short; generate it again with scenario_variation)",
                          Location(path, lines, 1))


def _is_complete(text: str) -> bool:
    """Whether the text's last non-blank line is :data:`SCE_END` (model lines are indented or quoted)."""
    return text.rstrip().rpartition("\n")[2] == SCE_END


def _line_of_key(text: str, key: str) -> int:
    for number, line in enumerate(text.split("\n"), start=1):
        if line.startswith(key + ":"):
            return number
    return 1


def _declared_scenarios(model: str) -> list[str]:
    return re.findall(r"^scenario[ \t]+([A-Za-z_][\w.]*)", model, re.MULTILINE)


#: The first item of the reference's ``.sce``: its ``scenario_variation`` writes ``#<path>==<value>`` comment lines,
#: then a YAML list of its model tree, one single-key mapping per declaration (``- PhysicalTypeDeclaration:``).
_REFERENCE_ITEM = re.compile(r"- [A-Z][A-Za-z]*(?:Declaration|Directive|Extension|Inherits)\b")


def _reference_sce_line(text: str) -> int:
    """The line of the reference's first model item when ``text`` is a ``.sce`` the reference wrote, else 0.

    Only the head is read: its comment lines (``#CompilationUnit.…``) and the first line after them.
    """
    for number, line in enumerate(text.split("\n", 200)[:200], start=1):
        if line.startswith("#") or not line.strip():
            continue
        return number if _REFERENCE_ITEM.match(line) else 0
    return 0


def _reference_sce(path: str, line: int) -> SceFormatError:
    return SceFormatError(
        "written by the reference's scenario_variation (a YAML dump of its model tree), which this tool does not "
        "run: regenerate the variants from the .osc with our scenario_variation, which reads the same "
        "'keep(... in [...])'", Location(path, line, 1))


def _load(text: str, path: str) -> dict[str, Any]:
    """The header mapping of a ``.sce`` text, its format version and the type of each key checked."""
    declared = _DECLARED_VERSION.match(text)
    if declared is not None and int(declared.group(1)) >= 2 and not _is_complete(text):
        raise _truncated(text, path)
    data = load_plain(text)                 # the shape our writer gives, without YAML (None: anything else)
    if data is None:
        reference = _reference_sce_line(text)
        if reference:
            raise _reference_sce(path, reference)
        data = _load_yaml(text, path)
    where = Location(path, 1, 1)
    if not isinstance(data, dict):
        raise SceFormatError("not a .sce file: expected a YAML mapping with 'format_version' and 'model'", where)
    version = data.get("format_version")
    if version is None:
        raise SceFormatError("not a .sce file: 'format_version' is missing", where)
    if version not in SCE_READABLE_VERSIONS or isinstance(version, bool):
        readable = " and ".join(str(v) for v in SCE_READABLE_VERSIONS)
        raise SceFormatError(
            f"unsupported .sce format version {version!r}; this release reads versions {readable} "
            f"(regenerate the file with this release's scenario_variation)", where)
    if version >= 2 and not _is_complete(text):
        raise _truncated(text, path)
    _check_types(data, where)
    return data


def _check_types(data: dict[str, Any], where: Location) -> None:
    """Each required key is present with its type; ``parameters`` and ``index``, when given, have theirs."""
    for key, kind in _REQUIRED.items():
        if key not in data:
            raise SceFormatError(f"malformed .sce file: '{key}' is missing", where)
        if not isinstance(data[key], kind) or isinstance(data[key], bool):
            raise SceFormatError(
                f"malformed .sce file: '{key}' must be a {'mapping' if kind is dict else kind.__name__}", where)
    parameters = data.get("parameters")
    if parameters is not None and not isinstance(parameters, dict):
        raise SceFormatError("malformed .sce file: 'parameters' must be a mapping", where)
    index = data.get("index")
    if index is not None and (not isinstance(index, int) or isinstance(index, bool) or index < 0):
        raise SceFormatError(f"malformed .sce file: 'index' must be an integer, 0 or more (got {index!r})", where)


def parse_sce(text: str, path: str = "<sce>") -> SceDocument:
    """Read the text of a ``.sce`` file; ``source_dir`` is made absolute against ``path``'s folder.

    Raises :class:`~coverage_engine.errors.SceFormatError` for anything malformed, an unknown format
    version, a version 2 file without its closing line (truncated), or a ``scenario`` the model does
    not declare.
    """
    data = _load(text, path)
    version = data["format_version"]
    parameters = data.get("parameters")
    index = data.get("index")
    model = data["model"]
    scenario = data["scenario"]
    if scenario:
        scenarios = _declared_scenarios(model)
        if scenario not in scenarios:
            known = ", ".join(scenarios) if scenarios else "none"
            raise SceFormatError(f"malformed .sce file: scenario {scenario!r} is not declared in its model "
                                 f"(scenarios there: {known})", Location(path, _line_of_key(text, "scenario"), 11))
    first = _model_first_line(text)
    padded = "\n" * (first - 1) + model if first > 0 else model
    base = Path(path).parent if path and not path.startswith("<") else Path.cwd()
    source_dir = str((base / data["source_dir"]).resolve()) if data["source_dir"] else str(base.resolve())
    unknown = [k for k in data if k not in _REQUIRED and k not in _OPTIONAL]
    if unknown:
        key = str(unknown[0])
        known = ", ".join([*_REQUIRED, *_OPTIONAL])
        raise SceFormatError(f"malformed .sce file: unknown key '{key}' (a .sce file has {known})",
                             Location(path, _line_of_key(text, key), 1))
    extra: dict = {}
    return SceDocument(
        text=padded, source_dir=source_dir, scenario=scenario, assignment=dict(data["assignment"]),
        format_version=version, source=data["source"], source_sha256=data["source_sha256"],
        index=index, parameters=parameters, path=path, extra=extra, model_offset=max(first - 1, 0),
        domains=tuple(header_domains(text)))


#: The last few files read, by path and identity (size, modification time, inode): a run reads its
#: ``.sce`` twice (to load it and to name its report), and parsing YAML is the costly part.
_recent: dict[tuple, SceDocument] = {}


def read_sce(path: str | os.PathLike) -> SceDocument:
    """Load a ``.sce`` file written by ``scenario_variation`` (see the module docstring for the format)."""
    path = str(path)
    try:
        with open(path, encoding="utf-8") as handle:
            stat = os.fstat(handle.fileno())
            key = (path, stat.st_size, stat.st_mtime_ns, stat.st_ino)
            if key in _recent:
                return _recent[key]
            if stat.st_size > MAX_YAML_BYTES:
                raise SceFormatError(f"{path}: {stat.st_size:,} bytes, larger than the limit of "
                                     f"{mib(MAX_YAML_BYTES)} for a .sce file")
            text = handle.read(MAX_YAML_BYTES + 1)
    except FileNotFoundError as exc:
        raise SceFormatError(f"{path}: no such file") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise SceFormatError(f"{path}: cannot read .sce file: {exc}") from exc
    document = parse_sce(text, path)
    if len(_recent) >= 4:
        _recent.clear()
    _recent[key] = document
    return document
