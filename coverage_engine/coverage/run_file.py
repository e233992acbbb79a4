"""The per-run ``coverage.json``: build it while a run goes, write it atomically, read it back validated.

Schema (format ``scenario-coverage/run``, version 1) is documented in ``docs/coverage-json.md``. It
carries everything the merge needs without the ``.osc``: each item's value type (with an enum's
members), unit, range and ``every``, so buckets are built from the file alone.

The runtime (or any launched child, in any language) writes one file per run folder::

    builder = RunCoverageBuilder("cut_in", source="out/cut_in3.sce", variant="cut_in3",
                                 assignment={"cut_in.speed": 20.0})
    speed = builder.cover("speed", path="cut_in", value_type="float", unit="kph", range=(0, 120), every=20)
    side = builder.cover("side", path="cut_in", value_type=ValueType("enum", ("left", "right")))
    both = builder.cross("speed_x_side", ["speed", "side"], path="cut_in")
    ttc = builder.record("min_ttc", path="cut_in", value_type="float", unit="s", event="finish")
    speed.add(57.5); side.add("left"); both.add([57.5, "left"]); ttc.add(1.8)
    write_run_coverage(output_dir, builder.build("passed"))

``add`` is a bare ``list.append`` (cheap enough to call every tick); values are checked once, in
:meth:`RunCoverageBuilder.build`, by the same validation that reading applies, so a file this module
writes always reads back.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from coverage_engine.coverage.atomic import write_text_atomically
from coverage_engine.coverage.buckets import MAX_BUCKETS, default_every, range_bucket_count
from coverage_engine.coverage.errors import RunFileError, location
from coverage_engine.coverage.json_positions import line_column, locate
from coverage_engine.coverage.values import KINDS, ValueType

#: The file a run writes into its output folder.
RUN_FILE = "coverage.json"

FORMAT = "scenario-coverage/run"
FORMAT_VERSION = 1

#: A run's verdicts (the batch's ``timeout`` is an ``error``; a run that did not start is ``skipped``).
VERDICTS = ("passed", "failed", "error", "skipped")

#: Item kinds in the file (a cross is a ``cover`` with ``items``).
ITEM_KINDS = ("cover", "record")

#: Bounds: a larger file, more items or more samples is refused with a clear error.
MAX_FILE_BYTES = 32 * 1024 * 1024
MAX_ITEMS = 10_000
MAX_SAMPLES_PER_ITEM = 1_000_000
MAX_NAME_CHARS = 256
MAX_MEMBERS = 10_000
MAX_TEXT_CHARS = 4_096

@dataclass(frozen=True)
class RunInfo:
    """Which run the file belongs to and how it ended."""

    scenario: str
    verdict: str
    source: str | None = None
    variant: str | None = None
    assignment: Mapping[str, object] = field(default_factory=dict)
    reason: str | None = None
    started: str | None = None
    duration: float | None = None


@dataclass(frozen=True)
class ItemDecl:
    """What a cover or record item is: enough to bucket its samples without the ``.osc``."""

    name: str
    kind: str                                   # "cover" | "record"
    path: str = ""                              # scenario / actor path where the item is declared
    value_type: ValueType | None = None         # None for a cross
    unit: str | None = None
    range: tuple[float, float] | None = None
    every: float | None = None
    event: str = "end"
    text: str | None = None
    ignore: str | None = None
    items: tuple[str, ...] = ()                 # a cross: names of cover items of the same path

    @property
    def full_name(self) -> str:
        return f"{self.path}.{self.name}" if self.path else self.name

    @property
    def is_cross(self) -> bool:
        return bool(self.items)

    def signature(self) -> tuple:
        """What must agree between runs for their samples to share buckets."""
        return (self.kind, self.value_type, self.unit, self.range, self.every, self.items)


@dataclass(frozen=True)
class RunCoverage:
    """One run's coverage: the run, its items, and per item the samples and the count ignored at run time."""

    run: RunInfo
    items: tuple[ItemDecl, ...]
    samples: tuple[list, ...]
    ignored: tuple[int, ...]


# ------------------------------------------------------------------------------------------ validation
class _Invalid(Exception):
    def __init__(self, path: Sequence[str | int], message: str) -> None:
        super().__init__(message)
        self.path = tuple(path)
        self.message = message


def _path_text(path: Sequence[str | int]) -> str:
    out = ""
    for step in path:
        out += f"[{step}]" if isinstance(step, int) else (f".{step}" if out else step)
    return out


def _obj(value: object, path: tuple, what: str) -> dict:
    if not isinstance(value, dict):
        raise _Invalid(path, f"{what} must be an object")
    return value


def _str(value: object, path: tuple, *, optional: bool = False, limit: int = MAX_TEXT_CHARS) -> str | None:
    if value is None and optional:
        return None
    if not isinstance(value, str):
        raise _Invalid(path, "must be a string" + (" or null" if optional else ""))
    if len(value) > limit:
        raise _Invalid(path, f"is longer than {limit} characters")
    return value


def _number(value: object, path: tuple) -> float:
    if type(value) not in (int, float) or not math.isfinite(value):
        raise _Invalid(path, "must be a finite number")
    return value  # type: ignore[return-value]


def _unknown_keys(data: dict, allowed: set[str], path: tuple) -> None:
    for key in data:
        if key not in allowed:
            raise _Invalid((*path, key), f"unknown key '{key}' (known: {', '.join(sorted(allowed))})")


_RUN_KEYS = {"scenario", "verdict", "source", "variant", "assignment", "reason", "started", "duration"}
_ITEM_KEYS = {"name", "kind", "path", "type", "members", "unit", "range", "every", "event", "text", "ignore",
              "items", "samples", "ignored"}


def _run_info(data: object) -> RunInfo:
    p = ("run",)
    run = _obj(data, p, "'run'")
    _unknown_keys(run, _RUN_KEYS, p)
    if "scenario" not in run:
        raise _Invalid(p, "missing 'scenario'")
    verdict = run.get("verdict")
    if verdict not in VERDICTS:
        raise _Invalid((*p, "verdict"), f"must be one of {', '.join(VERDICTS)}")
    assignment = run.get("assignment") or {}
    _obj(assignment, (*p, "assignment"), "'assignment'")
    for key, value in assignment.items():
        if len(key) > MAX_NAME_CHARS:
            raise _Invalid((*p, "assignment", key), f"parameter names are at most {MAX_NAME_CHARS} characters")
        if not isinstance(value, (str, int, float, bool)) or (isinstance(value, float) and not math.isfinite(value)):
            raise _Invalid((*p, "assignment", key), "must be a string, number or boolean")
    duration = run.get("duration")
    if duration is not None and (_number(duration, (*p, "duration")) < 0):
        raise _Invalid((*p, "duration"), "must not be negative")
    return RunInfo(
        scenario=_str(run["scenario"], (*p, "scenario"), limit=MAX_NAME_CHARS) or "",
        verdict=verdict, source=_str(run.get("source"), (*p, "source"), optional=True),
        variant=_str(run.get("variant"), (*p, "variant"), optional=True, limit=MAX_NAME_CHARS),
        assignment=assignment, reason=_str(run.get("reason"), (*p, "reason"), optional=True),
        started=_str(run.get("started"), (*p, "started"), optional=True, limit=64), duration=duration)


def _value_type(item: dict, p: tuple) -> ValueType:
    kind = item.get("type")
    if kind not in KINDS:
        raise _Invalid((*p, "type"), f"must be one of {', '.join(KINDS)}")
    members = item.get("members")
    if kind != "enum":
        if members is not None:
            raise _Invalid((*p, "members"), "only an enum item has members")
        return ValueType(kind)
    if not isinstance(members, list) or not members:
        raise _Invalid((*p, "members"), "an enum item needs its members: a non-empty list of names")
    if len(members) > MAX_MEMBERS:
        raise _Invalid((*p, "members"), f"more than {MAX_MEMBERS} members")
    for i, member in enumerate(members):
        _str(member, (*p, "members", i), limit=MAX_NAME_CHARS)
    if len(set(members)) != len(members):
        raise _Invalid((*p, "members"), "members must be distinct")
    return ValueType("enum", tuple(members))


def _range(item: dict, value_type: ValueType, p: tuple) -> tuple[tuple[float, float] | None, float | None]:
    value_range, every = item.get("range"), item.get("every")
    if value_range is None:
        if every is not None:
            raise _Invalid((*p, "every"), "'every' needs a 'range'")
        return None, None
    if not value_type.numeric:
        raise _Invalid((*p, "range"), f"a range needs a numeric item, not {value_type.kind}")
    if item.get("kind") != "cover":
        raise _Invalid((*p, "range"), "only cover items have a range")
    if not isinstance(value_range, list) or len(value_range) != 2:
        raise _Invalid((*p, "range"), "must be [low, high]")
    low, high = (_number(v, (*p, "range", i)) for i, v in enumerate(value_range))
    if low > high:
        raise _Invalid((*p, "range"), f"low {low} is above high {high}")
    if every is not None:
        every = _number(every, (*p, "every"))
        if every <= 0:
            raise _Invalid((*p, "every"), "must be above 0")
        if value_type.kind == "int" and not float(every).is_integer():
            raise _Invalid((*p, "every"), "an int item's buckets hold whole numbers: 'every' must be whole")
    count = range_bucket_count(value_type.kind, low, high, every or default_every(value_type.kind, low, high))
    if count > MAX_BUCKETS:
        raise _Invalid((*p, "every"), f"[{low}..{high}] every {every} makes {count} buckets; at most {MAX_BUCKETS}")
    return (low, high), every


def _item(data: object, index: int) -> tuple[ItemDecl, list, int]:
    p: tuple = ("items", index)
    item = _obj(data, p, "an item")
    _unknown_keys(item, _ITEM_KEYS, p)
    name = _str(item.get("name"), (*p, "name"), limit=MAX_NAME_CHARS)
    if not name:
        raise _Invalid((*p, "name"), "must not be empty")
    kind = item.get("kind")
    if kind not in ITEM_KINDS:
        raise _Invalid((*p, "kind"), f"must be one of {', '.join(ITEM_KINDS)}")
    path = _str(item.get("path", ""), (*p, "path"), limit=MAX_NAME_CHARS) or ""
    components = item.get("items")
    value_type: ValueType | None = None
    value_range, every = None, None
    if components is not None:
        if kind != "cover":
            raise _Invalid((*p, "items"), "only a cover item can cross other items")
        if not isinstance(components, list) or len(components) < 2:
            raise _Invalid((*p, "items"), "a cross names at least two items")
        for i, component in enumerate(components):
            _str(component, (*p, "items", i), limit=MAX_NAME_CHARS)
        for key in ("type", "members", "unit", "range", "every", "ignore"):
            if key in item:
                raise _Invalid((*p, key), f"a cross has no '{key}' (its items have)")
    else:
        value_type = _value_type(item, p)
        value_range, every = _range(item, value_type, p)
    samples = item.get("samples", [])
    if not isinstance(samples, list):
        raise _Invalid((*p, "samples"), "must be a list")
    if len(samples) > MAX_SAMPLES_PER_ITEM:
        raise _Invalid((*p, "samples"), f"more than {MAX_SAMPLES_PER_ITEM} samples")
    ignored = item.get("ignored", 0)
    if type(ignored) is not int or ignored < 0:
        raise _Invalid((*p, "ignored"), "must be a whole number of samples, 0 or more")
    decl = ItemDecl(
        name=name, kind=kind, path=path, value_type=value_type,
        unit=_str(item.get("unit"), (*p, "unit"), optional=True, limit=64), range=value_range, every=every,
        event=_str(item.get("event", "end"), (*p, "event"), limit=MAX_NAME_CHARS) or "end",
        text=_str(item.get("text"), (*p, "text"), optional=True),
        ignore=_str(item.get("ignore"), (*p, "ignore"), optional=True),
        items=tuple(components or ()))
    return decl, samples, ignored


def _check_samples(decls: list[ItemDecl], samples: list[list]) -> None:
    by_name = {(d.path, d.name): d for d in decls}
    for index, (decl, values) in enumerate(zip(decls, samples, strict=True)):
        p = ("items", index)
        if decl.is_cross:
            types = []
            for i, component in enumerate(decl.items):
                target = by_name.get((decl.path, component))
                if target is None:
                    raise _Invalid((*p, "items", i), f"no item '{component}' at path '{decl.path}' in this file")
                if target.kind != "cover" or target.is_cross:
                    raise _Invalid((*p, "items", i), f"'{component}' is not a cover item (a cross takes cover items)")
                types.append(target.value_type)
            for s, value in enumerate(values):
                if not isinstance(value, list) or len(value) != len(types):
                    raise _Invalid((*p, "samples", s), f"a sample of this cross is a list of {len(types)} values")
                for c, (part, vt) in enumerate(zip(value, types, strict=True)):
                    if not vt.accepts(part):
                        raise _Invalid((*p, "samples", s, c), f"{part!r} is not a {vt.describe()} value")
            continue
        accepts = decl.value_type.accepts  # type: ignore[union-attr]
        for s, value in enumerate(values):
            if not accepts(value):
                raise _Invalid((*p, "samples", s),
                               f"{value!r} is not a {decl.value_type.describe()} value")  # type: ignore[union-attr]


def _validate(doc: object) -> RunCoverage:
    top = _obj(doc, (), "coverage.json")
    if top.get("format") != FORMAT:
        raise _Invalid(("format",) if "format" in top else (), f"not a run coverage file (format must be '{FORMAT}')")
    version = top.get("format_version")
    if type(version) is not int:
        raise _Invalid(("format_version",), "must be a whole number")
    if version != FORMAT_VERSION:
        raise _Invalid(("format_version",), f"format_version {version} is not read by this release "
                                            f"(it reads {FORMAT_VERSION})")
    _unknown_keys(top, {"format", "format_version", "run", "items"}, ())
    run = _run_info(top.get("run"))
    items = top.get("items", [])
    if not isinstance(items, list):
        raise _Invalid(("items",), "must be a list")
    if len(items) > MAX_ITEMS:
        raise _Invalid(("items",), f"more than {MAX_ITEMS} items")
    decls, samples, ignored = [], [], []
    seen: dict[str, int] = {}
    for index, data in enumerate(items):
        decl, values, dropped = _item(data, index)
        if decl.full_name in seen:
            raise _Invalid(("items", index, "name"),
                           f"item '{decl.full_name}' is declared twice (first as items[{seen[decl.full_name]}])")
        seen[decl.full_name] = index
        decls.append(decl)
        samples.append(values)
        ignored.append(dropped)
    _check_samples(decls, samples)
    return RunCoverage(run=run, items=tuple(decls), samples=tuple(samples), ignored=tuple(ignored))


def parse_declarations(items: Sequence[Mapping[str, Any]], origin: str = RUN_FILE) -> tuple[ItemDecl, ...]:
    """Item declarations (``items`` of a coverage document without samples), validated like a file's."""
    doc = {"format": FORMAT, "format_version": FORMAT_VERSION, "run": {"scenario": "", "verdict": "passed"},
           "items": [{k: v for k, v in item.items() if k not in ("samples", "ignored")} for item in items]}
    try:
        return _validate(doc).items
    except _Invalid as exc:
        raise RunFileError(f"{_path_text(exc.path)}: {exc.message}", location(origin)) from None


# ------------------------------------------------------------------------------------------ reading
def parse_run_coverage(text: str, filename: str = RUN_FILE) -> RunCoverage:
    """Decode and validate the text of a ``coverage.json``; errors point at the bad value."""
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise RunFileError(f"not valid JSON: {exc.msg}", location(filename, exc.lineno, exc.colno)) from None
    except RecursionError:
        raise RunFileError("nested too deeply", location(filename)) from None
    try:
        return _validate(doc)
    except _Invalid as exc:
        where = locate(text, exc.path) or (0, 0)
        source_line = text.splitlines()[where[0] - 1] if where[0] else None
        if source_line is not None and len(source_line) > 200:
            source_line = None
        prefix = f"{_path_text(exc.path)}: " if exc.path else ""
        raise RunFileError(prefix + exc.message, location(filename, *where), source_line=source_line) from None


def read_run_coverage(path: str | os.PathLike[str], max_bytes: int = MAX_FILE_BYTES) -> RunCoverage:
    """Read and validate the ``coverage.json`` at ``path`` (at most ``max_bytes``)."""
    name = os.fspath(path)
    try:
        with open(name, "rb") as handle:
            data = handle.read(max_bytes + 1)
    except OSError as exc:
        raise RunFileError(f"cannot read: {exc.strerror or exc}", location(name)) from None
    if len(data) > max_bytes:
        raise RunFileError(f"larger than {max_bytes} bytes", location(name))
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line, column = line_column(data[:exc.start].decode("utf-8", "replace"), exc.start)
        raise RunFileError("not UTF-8 text", location(name, line, column)) from None
    return parse_run_coverage(text, name)


# ------------------------------------------------------------------------------------------ writing
def run_coverage_dict(run: RunCoverage) -> dict[str, Any]:
    """The JSON document of ``run`` (what :func:`write_run_coverage` writes)."""
    info = run.run
    run_doc: dict[str, Any] = {"scenario": info.scenario, "verdict": info.verdict}
    for key in ("source", "variant", "reason", "started", "duration"):
        value = getattr(info, key)
        if value is not None:
            run_doc[key] = value
    run_doc["assignment"] = dict(info.assignment)
    items = []
    for decl, values, dropped in zip(run.items, run.samples, run.ignored, strict=True):
        item: dict[str, Any] = {"name": decl.name, "kind": decl.kind, "path": decl.path}
        if decl.is_cross:
            item["items"] = list(decl.items)
        else:
            assert decl.value_type is not None
            item["type"] = decl.value_type.kind
            if decl.value_type.kind == "enum":
                item["members"] = list(decl.value_type.members)
            if decl.unit is not None:
                item["unit"] = decl.unit
            if decl.range is not None:
                item["range"] = list(decl.range)
            if decl.every is not None:
                item["every"] = decl.every
            if decl.ignore is not None:
                item["ignore"] = decl.ignore
        item["event"] = decl.event
        if decl.text is not None:
            item["text"] = decl.text
        if dropped:
            item["ignored"] = dropped
        item["samples"] = values
        items.append(item)
    return {"format": FORMAT, "format_version": FORMAT_VERSION, "run": run_doc, "items": items}


def run_coverage_text(run: RunCoverage) -> str:
    """The file's text: the header and the run on their own lines, then one line per item."""
    doc = run_coverage_dict(run)
    dumps = json.dumps
    lines = [f'{{"format": {dumps(doc["format"])}, "format_version": {doc["format_version"]},',
             f' "run": {dumps(doc["run"], ensure_ascii=False)},']
    if doc["items"]:
        body = ",\n".join("  " + dumps(item, ensure_ascii=False, allow_nan=False) for item in doc["items"])
        lines.append(' "items": [\n' + body + "\n ]}")
    else:
        lines.append(' "items": []}')
    return "\n".join(lines) + "\n"


def write_run_coverage(target: str | os.PathLike[str], run: RunCoverage) -> Path:
    """Write ``run`` to ``target`` (a file, or a folder to hold :data:`RUN_FILE`) atomically; returns the path.

    The text goes to a new temporary file in the same folder, is flushed to disk and then renamed over
    the target, so a reader (or a crash) never sees half a file; an existing link at the target is
    replaced, never followed.
    """
    path = Path(target)
    if path.is_dir():
        path = path / RUN_FILE
    return write_text_atomically(path, run_coverage_text(run))


# ------------------------------------------------------------------------------------------ building
class ItemSamples:
    """The samples of one item during a run: ``add(value)`` appends, ``drop()`` counts one ``ignore``d."""

    __slots__ = ("decl", "values", "ignored", "add")

    def __init__(self, decl: ItemDecl) -> None:
        self.decl = decl
        self.values: list = []
        self.ignored = 0
        self.add = self.values.append

    def drop(self) -> None:
        """A sample the item's ``ignore:`` condition matched (kept out of the buckets, but counted)."""
        self.ignored += 1


def _as_type(value_type: ValueType | str) -> ValueType:
    return value_type if isinstance(value_type, ValueType) else ValueType(value_type)


class RunCoverageBuilder:
    """Collects a run's items and samples; :meth:`build` checks them and returns the :class:`RunCoverage`."""

    def __init__(self, scenario: str, *, source: str | None = None, variant: str | None = None,
                 assignment: Mapping[str, object] | None = None) -> None:
        self.scenario, self.source, self.variant = scenario, source, variant
        self.assignment = dict(assignment or {})
        self._items: list[ItemSamples] = []

    def _declare(self, decl: ItemDecl) -> ItemSamples:
        sampler = ItemSamples(decl)
        self._items.append(sampler)
        return sampler

    def cover(self, name: str, *, value_type: ValueType | str, path: str = "", unit: str | None = None,
              range: tuple[float, float] | None = None, every: float | None = None,  # noqa: A002
              event: str = "end", text: str | None = None, ignore: str | None = None) -> ItemSamples:
        """Declare a cover item; returns its sampler."""
        return self._declare(ItemDecl(name, "cover", path, _as_type(value_type), unit,
                                      None if range is None else (range[0], range[1]), every, event, text, ignore))

    def record(self, name: str, *, value_type: ValueType | str, path: str = "", unit: str | None = None,
               event: str = "end", text: str | None = None) -> ItemSamples:
        """Declare a record item (raw values: min / median / max in the report)."""
        return self._declare(ItemDecl(name, "record", path, _as_type(value_type), unit, event=event, text=text))

    def cross(self, name: str, items: Sequence[str], *, path: str = "", event: str = "end",
              text: str | None = None) -> ItemSamples:
        """Declare a cross of cover items of the same ``path``; each sample is a list, one value per item."""
        return self._declare(ItemDecl(name, "cover", path, event=event, text=text, items=tuple(items)))

    def build(self, verdict: str, reason: str | None = None, *, started: str | None = None,
              duration: float | None = None) -> RunCoverage:
        """The run's coverage, validated (:class:`RunFileError` names the bad item or sample).

        Non-finite float samples (``nan``, ``inf``) cannot be JSON values: they are counted as ignored.
        """
        samples, ignored = [], []
        for sampler in self._items:
            values, dropped = sampler.values, sampler.ignored
            vt = sampler.decl.value_type
            if vt is not None and vt.kind == "float":
                finite = [v for v in values if not (isinstance(v, float) and not math.isfinite(v))]
                dropped += len(values) - len(finite)
                values = finite
            samples.append(values)
            ignored.append(dropped)
        run = RunCoverage(
            run=RunInfo(scenario=self.scenario, verdict=verdict, source=self.source, variant=self.variant,
                        assignment=self.assignment, reason=reason, started=started, duration=duration),
            items=tuple(s.decl for s in self._items), samples=tuple(samples), ignored=tuple(ignored))
        try:
            return _validate(run_coverage_dict(run))
        except _Invalid as exc:
            raise RunFileError(f"{_path_text(exc.path)}: {exc.message}") from None
