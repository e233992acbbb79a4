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
from pathlib import Path
from typing import Any

from coverage_engine.coverage.errors import RunFileError
from coverage_engine.coverage.json_positions import line_column, locate
from coverage_engine.coverage.run_records import (  # noqa: F401 - re-exported: the file's public records
    FORMAT,
    FORMAT_VERSION,
    MAX_FILE_BYTES,
    UNSAMPLED_VERSION,
    VERDICTS,
    ItemDecl,
    RunCoverage,
    RunInfo,
)
from coverage_engine.coverage.run_schema import Invalid, path_text, validate
from coverage_engine.coverage.values import ValueType
from coverage_engine.location import Location
from coverage_engine.results.atomic import write_text_atomically
from coverage_engine.results.files import COVERAGE_FILE


def parse_declarations(items: Sequence[Mapping[str, Any]], origin: str = COVERAGE_FILE) -> tuple[ItemDecl, ...]:
    """Item declarations (``items`` of a coverage document without samples), validated like a file's."""
    doc = {"format": FORMAT, "format_version": FORMAT_VERSION, "run": {"scenario": "", "verdict": "passed"},
           "items": [{k: v for k, v in item.items() if k not in ("samples", "ignored")} for item in items]}
    try:
        return validate(doc).items
    except Invalid as exc:
        raise RunFileError(f"{path_text(exc.path)}: {exc.message}", Location.whole_file(origin)) from None


# ------------------------------------------------------------------------------------------ reading
def parse_run_coverage(text: str, filename: str = COVERAGE_FILE) -> RunCoverage:
    """Decode and validate the text of a ``coverage.json``; errors point at the bad value."""
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise RunFileError(f"not valid JSON: {exc.msg}", Location.at(filename, exc.lineno, exc.colno)) from None
    except RecursionError:
        raise RunFileError("nested too deeply", Location.whole_file(filename)) from None
    try:
        return validate(doc)
    except Invalid as exc:
        where = locate(text, exc.path) or (0, 0)
        source_line = text.splitlines()[where[0] - 1] if where[0] else None
        if source_line is not None and len(source_line) > 200:
            source_line = None
        prefix = f"{path_text(exc.path)}: " if exc.path else ""
        raise RunFileError(prefix + exc.message, Location.at(filename, *where), source_line=source_line) from None


def read_run_coverage(path: str | os.PathLike[str], max_bytes: int = MAX_FILE_BYTES) -> RunCoverage:
    """Read and validate the ``coverage.json`` at ``path`` (at most ``max_bytes``)."""
    name = os.fspath(path)
    try:
        with open(name, "rb") as handle:
            data = handle.read(max_bytes + 1)
    except OSError as exc:
        raise RunFileError(f"cannot read: {exc.strerror or exc}", Location.whole_file(name)) from None
    if len(data) > max_bytes:
        raise RunFileError(f"larger than {max_bytes} bytes", Location.whole_file(name))
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line, column = line_column(data[:exc.start].decode("utf-8", "replace"), exc.start)
        raise RunFileError("not UTF-8 text", Location.at(name, line, column)) from None
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
    unsampled = run.unsampled or tuple([] for _ in run.items)
    for decl, values, dropped, missed in zip(run.items, run.samples, run.ignored, unsampled, strict=True):
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
        if missed:
            item["unsampled"] = missed
        items.append(item)
    version = UNSAMPLED_VERSION if any(run.unsampled) else FORMAT_VERSION
    return {"format": FORMAT, "format_version": version, "run": run_doc, "items": items}


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
    """Write ``run`` to ``target`` (a file, or a folder to hold :data:`COVERAGE_FILE`) atomically; returns the path.

    The text goes to a new temporary file in the same folder, is flushed to disk and then renamed over
    the target, so a reader (or a crash) never sees half a file; an existing link at the target is
    replaced, never followed.
    """
    path = Path(target)
    if path.is_dir():
        path = path / COVERAGE_FILE
    return write_text_atomically(path, run_coverage_text(run))


# ------------------------------------------------------------------------------------------ building
class ItemSamples:
    """The samples of one item during a run: ``add(value)`` appends, ``drop()`` counts one ``ignore``d."""

    __slots__ = ("decl", "values", "ignored", "add", "unsampled")

    def __init__(self, decl: ItemDecl) -> None:
        self.decl = decl
        self.values: list = []
        self.ignored = 0
        self.add = self.values.append
        self.unsampled: list = []      # values at a failure, for an item whose event never came

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
        samples, ignored, unsampled = [], [], []
        for sampler in self._items:
            unsampled.append([v for v in sampler.unsampled if not (isinstance(v, float) and not math.isfinite(v))])
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
            items=tuple(s.decl for s in self._items), samples=tuple(samples), ignored=tuple(ignored),
            unsampled=tuple(unsampled) if any(unsampled) else ())
        try:
            return validate(run_coverage_dict(run))
        except Invalid as exc:
            raise RunFileError(f"{path_text(exc.path)}: {exc.message}") from None
