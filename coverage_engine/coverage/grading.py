"""Turn the merge's counts into the report: buckets in order, targets, grades, holes, record statistics.

An item's grade is its covered buckets over its buckets (a bucket is covered when its hits reach the
plan's ``at_least``, 1 by default); the overall grade is the mean of the item grades weighted by the
plan (weight 1 by default, 0 leaves an item out). Record items have no grade. A cross with more than
:data:`MAX_CROSS_CELLS` cells is listed without a grid and not graded.
"""

from __future__ import annotations

import gc
import math
import re
from array import array
from collections.abc import Hashable, Mapping, Sequence
from dataclasses import replace
from itertools import islice

from coverage_engine.coverage.buckets import Bucket, RangeBuckets
from coverage_engine.coverage.input_domains import InputValueBuckets
from coverage_engine.coverage.merge import INPUT_PREFIX, CoverageMerger, ItemCounts
from coverage_engine.coverage.model import (
    KIND_ORDER,
    MAX_POINTS,
    BucketResult,
    CoverageReport,
    CrossGrid,
    Extremes,
    ItemResult,
    RecordSummary,
    RunTable,
)
from coverage_engine.coverage.plan import CoveragePlan
from coverage_engine.coverage.runs import REPORT_VERDICTS, RunSource
from coverage_engine.domains import InputDomain, drawn_units_of
from coverage_engine.results.verdicts import FAILING

#: Most cells a cross may have to be graded and drawn.
MAX_CROSS_CELLS = 10_000

#: Runs merged together (column by column); bounds the memory a chunk holds.
CHUNK_RUNS = 2000

#: Values of a non-numeric record item listed.
TOP_VALUES = 10


def natural_key(name: str) -> list:
    """``cut_in2`` before ``cut_in10``: digits compare as numbers."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", name)]


class _Buckets:
    """Builds :class:`BucketResult` records; failing runs are listed in natural order of their names.

    ``declared``: per varied parameter, what its variation declared and the ``every`` of a ``cover()`` of
    it in the same unit (:func:`declarations`), from which its buckets are made."""

    def __init__(self, names: list[str], verdicts: list[str],
                 declared: Mapping[str, tuple[InputDomain, float | None]] | None = None) -> None:
        self.names = names
        self.declared = declared or {}
        failing = [i for i, v in enumerate(verdicts) if v in FAILING]
        failing.sort(key=lambda i: natural_key(names[i]))
        self.rank = array("q", range(len(names)))    # runs that did not fail keep their own order
        for position, run in enumerate(failing):
            self.rank[run] = position - len(failing)

    def order(self, runs: list[int]) -> tuple[int, ...]:
        unique = set(runs)
        if len(unique) < 2:
            return tuple(unique)
        return tuple(sorted(unique, key=self.rank.__getitem__))

    def domain_of(self, counts: ItemCounts) -> InputDomain | None:
        """What the variation declared for a varied parameter's item (None for any other item)."""
        if counts.kind != "input":
            return None
        found = self.declared.get(counts.name[len(INPUT_PREFIX):])
        return found[0] if found else None

    def definitions(self, counts: ItemCounts, keys: list[Hashable]) -> tuple[list[Bucket], dict[Hashable, int]]:
        """The buckets of ``counts`` and the bucket of each of ``keys``."""
        bucketing = counts.plain_bucketing
        if isinstance(bucketing, InputValueBuckets):
            found = self.declared.get(counts.name[len(INPUT_PREFIX):])
            return bucketing.finish(keys, *found) if found else bucketing.finish(keys)
        return bucketing.finish(keys)

    def make(self, label: str, stats: list[int], failing: list[int], target: int, low: float | None = None,
             high: float | None = None, failed_here: list[int] | None = None) -> BucketResult:
        return BucketResult(label=label, hits=stats[0], passed=stats[1], failed=stats[2], errored=stats[3],
                            target=target, failing_runs=self.order(failing), low=low, high=high,
                            failed_here=self.order(failed_here) if failed_here else ())


def _plain_buckets(counts: ItemCounts, target: int, make: _Buckets) -> tuple[list[BucketResult], list[str]]:
    defs, index = make.definitions(counts, list(counts.stats))
    sums = [[0, 0, 0, 0] for _ in defs]
    failing: list[list[int]] = [[] for _ in defs]
    here: list[list[int]] = [[] for _ in defs]
    for key, st in counts.stats.items():
        i = index[key]
        row = sums[i]
        for s in range(4):
            row[s] += st[s]
        runs = counts.failing.get(key)
        if runs:
            failing[i].extend(runs)
    for key, runs in counts.failed_here.items():
        if key in index:
            here[index[key]].extend(runs)
    labels = [d.label for d in defs]
    return [make.make(d.label, sums[i], failing[i], target, d.low, d.high, here[i])
            for i, d in enumerate(defs)], labels


def _component_axis(component: ItemCounts, extra_keys: set, make: _Buckets) -> tuple[list[str], dict[Hashable, int]]:
    keys = list(component.stats) + [k for k in extra_keys if k not in component.stats]
    defs, index = make.definitions(component, keys)
    return [d.label for d in defs], index


def _parts(key: Hashable) -> tuple[Hashable, ...]:
    """The components' keys in the key of a cross's bucket (a tuple: see ``CrossBuckets.key``)."""
    assert isinstance(key, tuple), key
    return key


def _cross_buckets(counts: ItemCounts, target: int, make: _Buckets) -> tuple[list[BucketResult], CrossGrid | None, list[str]]:
    axes = counts.components
    extra: list[set] = [set() for _ in axes]
    for key in counts.stats:
        for position, part in enumerate(_parts(key)):
            extra[position].add(part)
    labels, indexes = [], []
    for component, keys in zip(axes, extra, strict=True):
        axis_labels, index = _component_axis(component, keys, make)
        labels.append(axis_labels)
        indexes.append(index)
    cells = math.prod(len(axis) for axis in labels)
    grid = CrossGrid(axes=tuple(c.name for c in axes), labels=tuple(tuple(axis) for axis in labels))
    if cells > MAX_CROSS_CELLS:
        return [], None, [f"{cells} cells are more than {MAX_CROSS_CELLS}: not drawn, not graded"]
    sums = [[0, 0, 0, 0] for _ in range(cells)]
    failing: list[list[int]] = [[] for _ in range(cells)]
    for key, st in counts.stats.items():
        flat = 0
        for position, part in enumerate(_parts(key)):
            flat = flat * len(labels[position]) + indexes[position][part]
        row = sums[flat]
        for s in range(4):
            row[s] += st[s]
        runs = counts.failing.get(key)
        if runs:
            failing[flat].extend(runs)
    here: dict[int, list[int]] = {}
    for key, runs in counts.failed_here.items():
        try:
            flat = 0
            for position, part in enumerate(_parts(key)):
                flat = flat * len(labels[position]) + indexes[position][part]
        except KeyError:
            continue
        here.setdefault(flat, []).extend(runs)
    buckets = []
    for flat in range(cells):
        parts, rest = [], flat
        for axis in reversed(labels):
            rest, i = divmod(rest, len(axis))
            parts.append(axis[i])
        buckets.append(make.make(" × ".join(reversed(parts)), sums[flat], failing[flat], target,
                                 failed_here=here.get(flat)))
    return buckets, grid, []


def _record(counts: ItemCounts) -> RecordSummary:
    values = counts.values
    if len(values):
        low = min(range(len(values)), key=values.__getitem__)
        high = max(range(len(values)), key=values.__getitem__)
        extremes = Extremes(minimum=values[low], min_run=counts.value_runs[low], median=_median(values),
                            maximum=values[high], max_run=counts.value_runs[high])
        return RecordSummary(count=len(values), extremes=extremes)
    top = tuple((str(v), n) for v, n in counts.others.most_common(TOP_VALUES))
    return RecordSummary(count=sum(counts.others.values()), top_values=top)


def _scatter(counts: ItemCounts, names: list[str]) -> tuple[tuple[float, float, str, str], ...]:
    """The runs of a cross of two drawn ranges as points (each drawn pair is its own key)."""
    points = []
    for key, st in counts.stats.items():
        x, y = _parts(key)
        if not isinstance(x, (int, float)) or not isinstance(y, (int, float)):
            continue
        verdict = "failed" if st[2] else "error" if st[3] else "passed" if st[1] else "pending"
        failing = counts.failing.get(key)
        points.append((float(x), float(y), verdict, names[failing[0]] if failing else ""))
    if len(points) > MAX_POINTS:          # every failure first, then passes evenly chosen
        bad = [p for p in points if p[2] != "passed"][:MAX_POINTS]
        good = [p for p in points if p[2] == "passed"]
        room = MAX_POINTS - len(bad)
        points = bad + (good[::math.ceil(len(good) / room)] if room > 0 and good else [])
    return tuple(points)


def declarations(merger: CoverageMerger, domains: Mapping[str, InputDomain]) \
        -> dict[str, tuple[InputDomain, float | None]]:
    """Per varied parameter: what its variation declared, and the ``every`` of a ``cover()`` of the same
    parameter in the same unit (it then sets the width of a range's buckets)."""
    covers = {c.decl.full_name: c.decl for c in merger.items.values() if c.kind == "cover" and c.decl is not None}
    found: dict[str, tuple[InputDomain, float | None]] = {}
    for key, domain in domains.items():
        decl = covers.get(key)
        every = decl.every if decl is not None and domain.is_range and (decl.unit or "") == domain.unit else None
        found[key] = (domain, every)
    return found


def _item(counts: ItemCounts, plan: CoveragePlan, make: _Buckets) -> ItemResult:
    settings = plan.for_item(counts.name)
    decl = counts.decl
    notes: list[str] = []
    grid = None
    record = None
    buckets: list[BucketResult] = []
    grade: float | None = None
    points: tuple[tuple[float, float, str, str], ...] = ()
    ranges: tuple[tuple[float, float, str], ...] = ()
    weight = settings.weight
    if counts.kind == "record":
        record = _record(counts)
    elif counts.kind in ("cross", "input_cross"):
        buckets, grid, notes = _cross_buckets(counts, settings.at_least, make)
        declared = [make.domain_of(c) for c in counts.components]
        if counts.kind == "input_cross" and all(d is not None and d.drawn for d in declared):
            points = _scatter(counts, make.names)
            ranges = tuple((d.low, d.high, d.unit) for d in declared if d is not None and d.low is not None
                           and d.high is not None)
            if not plan.names(counts.name):
                weight = 0.0
                notes.append("a cross of two sampled ranges: a scatter of the runs, not part of the overall "
                             "grade (a plan that names it grades it)")
    else:
        buckets, _ = _plain_buckets(counts, settings.at_least, make)
    if counts.kind != "record" and (buckets or grid is None and not notes):
        grade = 100.0 * sum(1 for b in buckets if b.covered) / len(buckets) if buckets else 0.0
    if counts.overflow:
        notes.append(f"more than {counts.limit} distinct values: {counts.overflow} sample(s) of new values ignored "
                     f"(give the item a range)")
    if counts.conflicts:
        notes.append("some runs declared it differently (type, unit, range, every or items); their samples "
                     "are left out")
    if counts.kind != "record" and not buckets and not notes:
        notes.append("no sample")
    value_type = decl.value_type if decl is not None else None
    return ItemResult(
        name=counts.name, kind=counts.kind, buckets=tuple(buckets), grade=grade, weight=weight,
        at_least=settings.at_least, path=decl.path if decl else "", unit=decl.unit if decl else None,
        type_text=value_type.describe() if value_type else None, text=decl.text if decl else None,
        event=decl.event if decl else None, ignore=decl.ignore if decl else None,
        range=decl.range if decl else None,
        every=counts.bucketing.every if isinstance(counts.bucketing, RangeBuckets) else None,
        samples=counts.samples, runs_sampled=counts.runs_sampled, ignored=counts.ignored, cross=grid,
        record=record, notes=tuple(notes), points=points, axis_ranges=ranges)


def overall_grade(items: list[ItemResult]) -> float | None:
    """The weighted mean of the graded items' grades (None when no item has weight)."""
    graded = [(item.grade, item.weight) for item in items if item.grade is not None]
    total = sum(weight for _, weight in graded)
    if total <= 0:
        return None
    return sum(grade * weight for grade, weight in graded) / total


def grade(merger: CoverageMerger, plan: CoveragePlan | None = None, *, source: str = "", complete: bool = True,
          notes: list[str] | None = None, root: str | None = None,
          warnings: list[str] | None = None, domains: Mapping[str, InputDomain] | None = None) -> CoverageReport:
    """The report of everything ``merger`` has read; ``domains``: what the variations declared."""
    plan = plan or CoveragePlan()
    domains = domains or {}
    order = {kind: i for i, kind in enumerate(KIND_ORDER)}
    counted = sorted(merger.items.values(), key=lambda c: order[c.kind])   # stable: first seen within a kind
    make = _Buckets(merger.run_names, merger.run_verdicts, declarations(merger, domains))
    items = [_item(c, plan, make) for c in counted]
    warnings = list(warnings or ()) + merger.finish_warnings()
    for entry in plan.unmatched([c.name for c in counted]):
        warnings.append(f"the plan names '{entry}', which matches no item")
    verdicts = {v: 0 for v in REPORT_VERDICTS}
    for verdict in merger.run_verdicts:
        verdicts[verdict] = verdicts.get(verdict, 0) + 1
    runs = RunTable(names=tuple(merger.run_names), verdicts=tuple(merger.run_verdicts),
                    reasons=tuple(merger.run_reasons), folders=tuple(merger.run_folders),
                    logs=tuple(merger.run_logs),
                    values=merger.failing_values,
                    drawn_units=drawn_units_of(domains.values()))
    return CoverageReport(source=source, complete=complete, runs=runs, verdict_counts=verdicts,
                          items=tuple(items), grade=overall_grade(items), notes=tuple(notes or ()),
                          warnings=tuple(warnings), plan_file=plan.file, root=root)


def build_report(source: RunSource, plan: CoveragePlan | None = None) -> CoverageReport:
    """Read every run of ``source`` and grade them: the one entry point of every report."""
    merger = CoverageMerger()
    collecting = gc.isenabled()
    gc.disable()   # the merge makes many small containers and no cycles: generational passes only cost time
    try:
        runs = iter(source.runs)
        while chunk := list(islice(runs, CHUNK_RUNS)):
            merger.add_chunk(chunk)
    finally:
        if collecting:
            gc.enable()
    report = grade(merger, plan, source=source.label, complete=source.complete, notes=source.notes,
                   root=source.root, warnings=source.warnings, domains=source.domains)
    if source.search is not None:
        report = replace(report, search=source.search.section(source.domains))
    return report


def _median(values: Sequence[float]) -> float:
    """``statistics.median``, imported when a record item has values (its import is a tenth of a batch's
    report start-up, and most batches record nothing)."""
    import statistics

    return statistics.median(values)
