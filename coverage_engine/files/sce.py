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

Every value is written by PyYAML's safe dumper (:func:`_quote`: strings double-quoted, so each
character YAML would change, such as NEL, LS, PS, BOM or a control character, is escaped), and the
file is put together from those pieces by :class:`SceTemplate`, which quotes each value once per
choice rather than once per variant: 100,000 variants stay a matter of seconds. Header comments are
one line of printable characters (anything else escaped), so they can never break the document.
"""

from __future__ import annotations

import os
import re
from array import array
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from coverage_engine.errors import SceFormatError
from coverage_engine.files.sce_plain import load_plain
from coverage_engine.lazy import NumberTexts, per_choice
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

#: Characters a YAML literal block cannot carry unchanged: anything but tab, line feed and printable
#: characters, and the printable ones YAML reads as line breaks (NEL, LS, PS) or as a byte order mark.
_BLOCK_UNSAFE = re.compile("[^\t\n\x20-\x7e\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]|[\x85\u2028\u2029\ufeff]")


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


def _double_quoted(dumper, data: str):
    return dumper.represent_scalar("tag:yaml.org,2002:str", data, style='"')


def _dumper():
    import yaml

    class SceDumper(yaml.SafeDumper):
        """The safe dumper, writing every string double-quoted (one line, every special character escaped)."""

    SceDumper.add_representer(str, _double_quoted)
    return SceDumper


_DUMPER = None


def _quote(value: object) -> str:
    """``value`` as one line of YAML flow text, written by PyYAML's safe dumper.

    Strings are double-quoted with every character YAML would change escaped (line breaks, NEL,
    LS/PS, BOM, control characters); floats keep their value (``1.0e+300``, ``-0.0``, ``.inf``, ``.nan``);
    mappings and lists are flow collections.
    """
    global _DUMPER
    fast = _quote_fast(value)
    if fast is not None:
        return fast
    import yaml

    if _DUMPER is None:
        _DUMPER = _dumper()
    text = yaml.dump(value, Dumper=_DUMPER, default_flow_style=True, allow_unicode=True, width=float("inf"))
    text = text.removesuffix("\n").removesuffix("\n...").rstrip("\n")
    if "\n" in text:                                   # cannot happen with an infinite width; never write one
        raise ValueError(f"value does not fit on one line: {value!r}")
    return text


#: Strings the fast path may write as JSON does: printable ASCII (JSON's escapes of ``"`` and ``\\`` are YAML's).
_PLAIN_ASCII = re.compile(r"[\x20-\x7e]*")


def _quote_fast(value: object) -> str | None:
    """What the safe dumper writes for the common values, without it (it costs ~50 µs a value: 100,000
    drawn values took seconds); None for anything else. The round-trip tests compare the two."""
    kind = type(value)
    if kind is int:
        return str(value)
    if kind is float:
        text = repr(value)
        # PyYAML reads a float only with a dot in its mantissa; inf, nan and exponents go the slow way.
        return text if "." in text and "e" not in text and "n" not in text else None
    if isinstance(value, str) and kind is str and _PLAIN_ASCII.fullmatch(value):
        import json

        return json.dumps(value)
    return None


def _indent_chunk(chunk: str, first: bool, last: bool) -> str:
    """Indent a piece of model text for the literal block (empty lines stay empty).

    A chunk ends where a substituted value begins, so a line break at its very end still starts a
    non-empty line; in the last chunk the final line break ends the block.
    """
    pattern = _LAST_BREAKS if last else _INNER_BREAKS
    indented = pattern.sub("\n  ", chunk)
    if first and not chunk.startswith("\n"):
        indented = "  " + indented
    return indented


_INNER_BREAKS = re.compile(r"\n(?!\n)")
_LAST_BREAKS = re.compile(r"\n(?![\n]|\Z)")


class SceTemplate:
    """Makes the ``.sce`` texts of all variants of one source file, fast.

    The concrete model is ``chunks[0] + slot_0 + chunks[1] + … + chunks[-1]`` where slot ``i`` is
    ``replacements[i][choice]``. Each dimension (the text ones first, in order, then the optional
    parameter-document one) has per choice: a key, the value as shown in the header comment, and the
    value stored in the assignment. Everything is quoted and indented once here; :meth:`render`
    only joins strings, so 100,000 variants cost little more than writing them.
    """

    def __init__(self, *, source: str, source_sha256: str, source_dir: str, scenario: str,
                 chunks: list[str], replacements: Sequence[Sequence[str]], keys: list[str],
                 shown: Sequence[Sequence[str]], stored: Sequence[Sequence[object]],
                 documents: Sequence[Mapping[str, object]] | None = None, note: str | None = None) -> None:
        model = "".join(chunks)
        # Listed values are checked one by one; a lazy slot holds drawn numbers (plain one-line text).
        self._block = _BLOCK_UNSAFE.search(model) is None and all(
            _BLOCK_UNSAFE.search(r) is None and "\n" not in r
            for slot in replacements if isinstance(slot, (list, tuple)) for r in slot)
        last = len(chunks) - 1
        if self._block:
            self._chunks = [_indent_chunk(c, i == 0, i == last) for i, c in enumerate(chunks)]
        else:
            self._chunks = list(chunks)
        self._replacements = replacements
        self._magic = f"{SCE_MAGIC}, format {SCE_FORMAT_VERSION}: variant "
        self._of = f" of {_one_line(Path(source).name)}\n" + (f"# {_one_line(note)}\n" if note else "")
        self._head = (
            f"format_version: {SCE_FORMAT_VERSION}\n"
            f"source: {_quote(source)}\n"
            f"source_sha256: {_quote(source_sha256)}\n"
            f"source_dir: {_quote(source_dir)}\n"
            f"scenario: {_quote(scenario)}\n"
            "index: "
        )
        self._comments = [_comments(key, texts) for key, texts in zip(keys, shown, strict=True)]
        self._entries = [_entries(key, values) for key, values in zip(keys, stored, strict=True)]
        self._documents = None if documents is None else [f"parameters: {_quote(d)}\n" for d in documents]
        self.text_dimensions = len(replacements)
        # Per dimension, the drawn numbers when each of its texts is a number in fixed text (else None).
        self._drawn = [drawn_numbers([self._comments[i], self._entries[i]]
                                     + ([replacements[i]] if i < len(replacements) else []))
                       for i in range(len(keys))]
        self._drawn_axes = [(axis, numbers) for axis, numbers in enumerate(self._drawn) if numbers is not None]

    def model_text(self, choices: tuple[int, ...] | list[int]) -> str:
        """The concrete ``.osc`` text for ``choices`` (not indented)."""
        if self._block:
            raise RuntimeError("model_text() is for the variation template, not the indented one")
        return _join(self._chunks, self._replacements, choices, self.spell_row(choices))

    def spell_row(self, choices: tuple[int, ...] | list[int]) -> list[str | None]:
        """Per dimension, the ``repr`` of the drawn number ``choices`` picks, when it is a plain decimal
        (see :class:`~coverage_engine.lazy.NumberTexts`); None for a listed dimension or another number.

        :meth:`render` and the caller's other texts of the row (the stored assignment) share it: a
        drawn number is spelled once per variant, not once per text that shows it.
        """
        spelled: list[str | None] = [None] * len(self._drawn)
        for axis, numbers in self._drawn_axes:
            text = repr(numbers[choices[axis]])
            if "." in text and "e" not in text and "n" not in text:    # a plain decimal
                spelled[axis] = text
        return spelled

    def render(self, index: int, choices: tuple[int, ...] | list[int],
               spelled: list[str | None] | None = None) -> str:
        """The ``.sce`` text of variant ``index`` made of ``choices`` (one choice index per dimension).

        ``spelled``: what :meth:`spell_row` gives for ``choices`` (computed here when not given).
        """
        if spelled is None:
            spelled = self.spell_row(choices)
        parts = [self._magic, str(index), self._of]
        _append_row(parts, self._comments, choices, spelled)
        parts += [self._head, str(index), "\n"]
        if self._entries:
            parts.append("assignment:\n")
            _append_row(parts, self._entries, choices, spelled)
        else:
            parts.append("assignment: {}\n")
        if self._documents is not None:
            parts.append(self._documents[choices[-1]])
        model = _join(self._chunks, self._replacements, choices, spelled)
        if self._block:
            parts += ["model: |2\n", model, _END_LINE]
        else:
            parts += ["model: ", _quote(model.rstrip("\n") + "\n"), "\n", _END_LINE]
        return "".join(parts)


def _append_row(parts: list[str], slots: Sequence[Sequence[str]], choices: Sequence[int],
                spelled: Sequence[str | None]) -> None:
    """Append each dimension's text for its choice; a drawn number uses its spelling from ``spelled``."""
    for slot, choice, number in zip(slots, choices, spelled, strict=False):
        if number is None:
            parts.append(slot[choice])
        else:
            parts += (slot.prefix, number, slot.suffix)  # type: ignore[attr-defined]


def drawn_numbers(slots: Sequence[Sequence[str]]) -> Sequence[float] | None:
    """The numbers behind ``slots`` when every one is a :class:`NumberTexts` over the same numbers."""
    numbers = [slot.numbers for slot in slots if isinstance(slot, NumberTexts)]
    if len(numbers) != len(slots) or not numbers or any(n is not numbers[0] for n in numbers):
        return None
    return numbers[0]


_END_LINE = SCE_END + "\n"


def _comments(key: str, texts: Sequence[str]) -> Sequence[str]:
    """The header comment line of each choice of one dimension (``# key = value``)."""
    head = f"# {_one_line(key)} = "
    if isinstance(texts, NumberTexts) and _PLAIN_WORD.fullmatch(texts.prefix + texts.suffix):
        return texts.around(head, "\n")            # a number's repr is one plain word too
    return per_choice(texts, lambda text: f"{head}{_one_line(text)}\n")


def _entries(key: str, values: Sequence[object]) -> Sequence[str]:
    """The assignment line of each choice of one dimension (``  "key": value``)."""
    head = f"  {_quote(key)}: "
    if isinstance(values, array) and values.typecode == "d":
        return NumberTexts(values, head, "\n", _quote)   # _quote spells a plain float as its repr
    return per_choice(values, lambda value: f"{head}{_quote(value)}\n")


def _join(chunks: list[str], replacements: Sequence[Sequence[str]], choices, spelled) -> str:
    if not replacements:
        return chunks[0]
    parts = [chunks[0]]
    for i, slot in enumerate(replacements):
        number = spelled[i]
        if number is None:
            parts.append(slot[choices[i]])
        else:
            parts += (slot.prefix, number, slot.suffix)  # type: ignore[attr-defined]
        parts.append(chunks[i + 1])
    return "".join(parts)


#: Characters a YAML stream may not contain anywhere, comments included (PyYAML's reader refuses them).
_NOT_PRINTABLE = re.compile("[^\x09\x0a\x0d\x20-\x7e\x85\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]|\ufeff")


#: Text that :func:`_one_line` leaves as it is: printable ASCII without blanks.
_PLAIN_WORD = re.compile(r"[\x21-\x7e]*")


def _one_line(text: str) -> str:
    """``text`` fit for a comment line: whitespace runs (line breaks, NEL, LS, PS) become one space and
    characters a YAML stream may not carry are written as escapes (``\\x07``)."""
    if _PLAIN_WORD.fullmatch(text):      # a number, a name: nothing to change (most values)
        return text
    joined = " ".join(text.split())
    return _NOT_PRINTABLE.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), joined)


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
    """One ``.sce`` text (for single files and tests; the generator uses :class:`SceTemplate`)."""
    keys = list(assignment)
    values = dict(assignment)
    if parameters is not None:
        keys.append("parameter_document")
        values["parameter_document"] = 0
    template = SceTemplate(
        source=source, source_sha256=source_sha256, source_dir=source_dir, scenario=scenario,
        chunks=[model_text.rstrip("\n") + "\n"], replacements=[], keys=keys,
        shown=[[shown.get(k, str(values[k]))] for k in keys], stored=[[values[k]] for k in keys],
        documents=None if parameters is None else [parameters])
    return template.render(index, [0] * len(keys))


def is_sce_text(head: str) -> bool:
    """Whether a file starting with ``head`` was written by ``scenario_variation``."""
    return head.startswith(SCE_MAGIC)


def _load_yaml(text: str, path: str):
    import yaml

    from coverage_engine.yaml_bounds import DuplicateKeyError, YamlLimitError, load_bounded, with_unique_keys

    loader = with_unique_keys(getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    try:
        return load_bounded(text, loader)
    except DuplicateKeyError as exc:
        raise SceFormatError(f"malformed .sce file: {exc}", Location(path, exc.line, exc.column)) from None
    except YamlLimitError as exc:
        where = Location(path, exc.line, exc.column) if exc.line else Location(path, 0, 0)
        raise SceFormatError(f"not a usable .sce file: {exc}", where) from None
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
        raise SceFormatError(f"not a valid .sce file: {exc}", Location(path, 0, 0)) from exc


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


def parse_sce(text: str, path: str = "<sce>") -> SceDocument:
    """Read the text of a ``.sce`` file; ``source_dir`` is made absolute against ``path``'s folder.

    Raises :class:`~coverage_engine.errors.SceFormatError` for anything malformed, an unknown format
    version, a version 2 file without its closing line (truncated), or a ``scenario`` the model does
    not declare.
    """
    declared = _DECLARED_VERSION.match(text)
    if declared is not None and int(declared.group(1)) >= 2 and not _is_complete(text):
        raise _truncated(text, path)
    data = load_plain(text)                 # the shape our writer gives, without YAML (None: anything else)
    if data is None:
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
        index=index, parameters=parameters, path=path, extra=extra)


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
            text = handle.read()
    except FileNotFoundError as exc:
        raise SceFormatError(f"{path}: no such file") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise SceFormatError(f"{path}: cannot read .sce file: {exc}") from exc
    document = parse_sce(text, path)
    if len(_recent) >= 4:
        _recent.clear()
    _recent[key] = document
    return document
