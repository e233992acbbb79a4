"""Writing ``.sce`` files: :class:`SceTemplate` for the variants of one source, :func:`render_sce` for one.

Every value is written by PyYAML's safe dumper (:func:`_quote`: strings double-quoted, so each
character YAML would change, such as NEL, LS, PS, BOM or a control character, is escaped), and the
file is put together from those pieces by :class:`SceTemplate`, which quotes each value once per
choice rather than once per variant: 100,000 variants stay a matter of seconds. Header comments are
one line of printable characters (anything else escaped), so they can never break the document.

The format itself (what each key means, how files are read) is described in
:mod:`coverage_engine.files.sce`.
"""

from __future__ import annotations

import os
import re
from array import array
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from coverage_engine.domains import InputDomain, domain_line, drawn_text
from coverage_engine.files.sce import SCE_END, SCE_FORMAT_VERSION, SCE_MAGIC
from coverage_engine.files.sce_plain import YAML_SPECIAL
from coverage_engine.lazy import Mapped, NumberTexts, per_choice, row_texts
from coverage_engine.proposals import Proposal, proposal_line

if TYPE_CHECKING:   # PyYAML is imported when a value first needs it
    import yaml

#: A model holding a character YAML reads specially cannot be a literal block: it is quoted instead.
_BLOCK_UNSAFE = YAML_SPECIAL


def _double_quoted(dumper: yaml.SafeDumper, data: str) -> yaml.ScalarNode:
    return dumper.represent_scalar("tag:yaml.org,2002:str", data, style='"')


def _dumper() -> type[yaml.SafeDumper]:
    import yaml

    class SceDumper(yaml.SafeDumper):
        """The safe dumper, writing every string double-quoted (one line, every special character escaped)."""

    SceDumper.add_representer(str, _double_quoted)
    return SceDumper


_DUMPER: type[yaml.SafeDumper] | None = None


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
                 documents: Sequence[Mapping[str, object]] | None = None, note: str | None = None,
                 domains: Sequence[InputDomain] = (), proposal: Proposal | None = None) -> None:
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
        self._domains = "".join(domain_line(d) for d in domains) + (proposal_line(proposal) if proposal else "")
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
        self._drawn = [_drawn_numbers([self._entries[i]]
                                     + ([replacements[i]] if i < len(replacements) else []))
                       for i in range(len(keys))]
        self._unspelled: list[str | None] = [None] * len(keys)   # header comments round drawn numbers
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
        parts += row_texts(self._comments, choices, self._unspelled)
        parts += [self._domains, self._head, str(index), "\n"]
        if self._entries:
            parts.append("assignment:\n")
            parts += row_texts(self._entries, choices, spelled)
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


def _drawn_numbers(slots: Sequence[Sequence[str]]) -> Sequence[float] | None:
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
        prefix, suffix = head + texts.prefix, texts.suffix + "\n"   # a drawn number: rounded, with its unit
        return Mapped(texts.numbers, lambda number: prefix + drawn_text(number) + suffix)
    return per_choice(texts, lambda text: f"{head}{_one_line(text)}\n")


def _entries(key: str, values: Sequence[object]) -> Sequence[str]:
    """The assignment line of each choice of one dimension (``  "key": value``)."""
    head = f"  {_quote(key)}: "
    if isinstance(values, array) and values.typecode == "d":
        return NumberTexts(values, head, "\n", _quote)   # _quote spells a plain float as its repr
    return per_choice(values, lambda value: f"{head}{_quote(value)}\n")


def _join(chunks: list[str], replacements: Sequence[Sequence[str]], choices: Sequence[int],
          spelled: Sequence[str | None]) -> str:
    parts = [chunks[0]]
    for text, chunk in zip(row_texts(replacements, choices, spelled), chunks[1:], strict=True):
        parts += (text, chunk)
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
