"""The ``.sce`` format: one concrete variant of an ``.osc`` scenario, as small human-readable YAML.

``scenario_variation`` writes one ``.sce`` per combination of varied values; ``scenario_execution``
loads it exactly like the ``.osc`` it came from (see :mod:`coverage_engine.loader`). A file looks like::

    # scenario_variation .sce, format 1: variant 1 of example.osc
    # example_variation.log.msg = "bar"
    format_version: 1
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

Why this shape:

* ``model`` is the concrete ``.osc`` text (each ``in [...]`` replaced by ``== value``), so imports such as
  ``import osc.helpers`` stay import lines: libraries are referenced by name, never copied, and a
  ``.sce`` stays a few hundred bytes.
* ``source_dir`` is where relative imports and external Python modules are found. It is written
  relative to the ``.sce``'s own folder when possible, so a checkout can move (or be mounted at another
  path on a batch host) and its ``.sce`` files still load; :func:`read_sce` returns it absolute.
* The model's lines are given back with as many blank lines in front as the block starts below the
  top of the file, so an error in a ``.sce`` names the ``.sce`` line the user sees.
* Everything written is deterministic (no time stamps): the SHA-256 of the text is the variant's
  identity in the store, and regenerating the same input gives byte-identical files.

Writing never goes through a YAML emitter: :class:`SceWriter` fills a template of pre-quoted parts,
which is what makes 100,000 variants a matter of seconds.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from coverage_engine.errors import SceFormatError
from coverage_engine.syntax import Location

#: The format version this release writes and reads.
SCE_FORMAT_VERSION = 1

#: First line of every file we write (also how an earlier generation's files are recognised).
SCE_MAGIC = "# scenario_variation .sce"

_REQUIRED = {
    "format_version": int,
    "source": str,
    "source_sha256": str,
    "source_dir": str,
    "scenario": str,
    "assignment": dict,
    "model": str,
}

#: Characters a YAML literal block can carry unchanged (printable, tab; no CR, no BOM, no NEL/LS/PS).
_BLOCK_UNSAFE = re.compile("[^\t\n\x20-\x7e\xa0-\ud7ff\ue000-\ufefe\uff00-\ufffd\U00010000-\U0010ffff]|[\x85]")


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


def _quote(value: object) -> str:
    """A YAML flow scalar for ``value`` (JSON is valid YAML; non-ASCII kept readable)."""
    return json.dumps(value, ensure_ascii=False)


def _model_block(text: str) -> str:
    """``model:`` as a literal block when the text allows it, else as a double-quoted scalar."""
    body = text.rstrip("\n") + "\n"
    if _BLOCK_UNSAFE.search(body) is None:
        return "model: |2\n" + "".join("  " + line + "\n" if line else "\n" for line in body[:-1].split("\n"))
    return "model: " + _quote(body) + "\n"


class SceWriter:
    """Makes ``.sce`` texts for the variants of one source file, fast.

    Everything that is the same for all variants (source name, hash, folder, scenario) is quoted once;
    :meth:`render` only joins strings. ``source_dir`` should already be the form to write (relative to
    the output folder, see :func:`relative_source_dir`).
    """

    def __init__(self, source: str, source_sha256: str, source_dir: str, scenario: str) -> None:
        self._head = (
            f"format_version: {SCE_FORMAT_VERSION}\n"
            f"source: {_quote(source)}\n"
            f"source_sha256: {_quote(source_sha256)}\n"
            f"source_dir: {_quote(source_dir)}\n"
            f"scenario: {_quote(scenario)}\n"
        )
        self._magic = f"{SCE_MAGIC}, format {SCE_FORMAT_VERSION}: variant "
        self._of = f" of {_one_line(Path(source).name)}\n"

    def render(self, index: int, assignment: Mapping[str, object], shown: Mapping[str, str],
               model_text: str, parameters: Mapping[str, object] | None = None) -> str:
        """The ``.sce`` text of variant ``index``.

        ``assignment`` maps ``scenario.path`` to the value stored (JSON-able); ``shown`` maps the same
        keys to the value as written in the source (for the header comments); ``model_text`` is the
        concrete ``.osc`` text; ``parameters`` the parameter document used, if any.
        """
        parts = [self._magic, str(index), self._of]
        for key, text in shown.items():
            parts.append(f"# {key} = {_one_line(text)}\n")
        parts.append(self._head)
        parts.append(f"index: {index}\n")
        if assignment:
            parts.append("assignment:\n")
            for key, value in assignment.items():
                parts.append(f"  {_quote(key)}: {_quote(value)}\n")
        else:
            parts.append("assignment: {}\n")
        if parameters is not None:
            parts.append(f"parameters: {_quote(parameters)}\n")
        parts.append(_model_block(model_text))
        return "".join(parts)


def _one_line(text: str) -> str:
    return " ".join(text.split())


def relative_source_dir(source_dir: str | os.PathLike, output_dir: str | os.PathLike) -> str:
    """``source_dir`` as written into a ``.sce`` in ``output_dir``: relative when possible, with ``/``."""
    source_dir = os.path.abspath(source_dir)
    try:
        rel = os.path.relpath(source_dir, os.path.abspath(output_dir))
    except ValueError:  # another drive on Windows
        return Path(source_dir).as_posix()
    return Path(rel).as_posix()


def render_sce(source: str, source_sha256: str, source_dir: str, scenario: str, index: int,
               assignment: Mapping[str, object], shown: Mapping[str, str], model_text: str,
               parameters: Mapping[str, object] | None = None) -> str:
    """One ``.sce`` text (convenience wrapper of :class:`SceWriter` for single files and tests)."""
    return SceWriter(source, source_sha256, source_dir, scenario).render(
        index, assignment, shown, model_text, parameters)


def is_sce_text(head: str) -> bool:
    """Whether a file starting with ``head`` was written by ``scenario_variation``."""
    return head.startswith(SCE_MAGIC)


def _load_yaml(text: str, path: str):
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    try:
        return yaml.load(text, Loader=loader)  # noqa: S506 - a safe loader
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        location = Location(path, mark.line + 1, mark.column + 1) if mark is not None else None
        raise SceFormatError(f"not a valid .sce file: {exc.problem or exc}", location) from exc
    except yaml.YAMLError as exc:
        raise SceFormatError(f"{path}: not a valid .sce file: {exc}") from exc


def _model_first_line(text: str) -> int:
    """1-based line of the ``.sce`` on which the model's first line stands (0 when not a block)."""
    for number, line in enumerate(text.split("\n"), start=1):
        if line.startswith("model:"):
            return number + 1 if line.rstrip().startswith("model: |") else 0
    return 0


def parse_sce(text: str, path: str = "<sce>") -> SceDocument:
    """Read the text of a ``.sce`` file; ``source_dir`` is made absolute against ``path``'s folder.

    Raises :class:`~coverage_engine.errors.SceFormatError` for anything malformed or an unknown
    format version.
    """
    data = _load_yaml(text, path)
    where = Location(path, 1, 1)
    if not isinstance(data, dict):
        raise SceFormatError("not a .sce file: expected a YAML mapping with 'format_version' and 'model'", where)
    version = data.get("format_version")
    if version is None:
        raise SceFormatError("not a .sce file: 'format_version' is missing", where)
    if version != SCE_FORMAT_VERSION or isinstance(version, bool):
        raise SceFormatError(
            f"unsupported .sce format version {version!r}; this release reads version {SCE_FORMAT_VERSION} "
            f"(regenerate the file with this release's scenario_variation)", where)
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
    if index is not None and (not isinstance(index, int) or isinstance(index, bool)):
        raise SceFormatError("malformed .sce file: 'index' must be an integer", where)
    first = _model_first_line(text)
    model = data["model"]
    padded = "\n" * (first - 1) + model if first > 0 else model
    base = Path(path).parent if path and not path.startswith("<") else Path.cwd()
    source_dir = str((base / data["source_dir"]).resolve()) if data["source_dir"] else str(base.resolve())
    extra = {k: v for k, v in data.items() if k not in _REQUIRED and k not in ("parameters", "index")}
    return SceDocument(
        text=padded, source_dir=source_dir, scenario=data["scenario"], assignment=dict(data["assignment"]),
        format_version=version, source=data["source"], source_sha256=data["source_sha256"],
        index=index, parameters=parameters, path=path, extra=extra)


def read_sce(path: str | os.PathLike) -> SceDocument:
    """Load a ``.sce`` file written by ``scenario_variation`` (see the module docstring for the format)."""
    path = str(path)
    try:
        with open(path, encoding="utf-8") as handle:
            text = handle.read()
    except FileNotFoundError as exc:
        raise SceFormatError(f"{path}: no such file") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise SceFormatError(f"{path}: cannot read .sce file: {exc}") from exc
    return parse_sce(text, path)
