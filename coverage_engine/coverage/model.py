"""The computed coverage: what every renderer shows, and nothing about how it is shown.

Built once by :func:`coverage_engine.coverage.grading.grade`; the terminal, JSON and HTML renderers
only read it (the way coverage.py's reports read its ``Analysis``). Grades are percentages.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from coverage_engine.coverage.buckets import value_label
from coverage_engine.coverage.search_rounds import SearchSection
from coverage_engine.domains import drawn_text
from coverage_engine.results.verdicts import FAILING

#: The prefix of the items of varied parameters (``input:<parameter>``).
INPUT_ITEM_PREFIX = "input:"

#: Most runs a scatter shows.
MAX_POINTS = 5_000

#: Item kinds, in the order reports list them.
KIND_ORDER = ("input", "input_cross", "cover", "cross", "record")

KIND_TITLES = {
    "input": "varied parameter",
    "input_cross": "cross of varied parameters",
    "cover": "cover item",
    "cross": "cross item",
    "record": "record item",
}


def short_name(name: str) -> str:
    """An item's or parameter's name without ``input:`` and its scenario (``input:cut_in.ego.speed`` →
    ``ego.speed``): how axes, columns and values name a parameter in a report."""
    return name.removeprefix(INPUT_ITEM_PREFIX).split(".", 1)[-1]


@dataclass(frozen=True)
class BucketResult:
    """One bucket: samples that fell in it (``hits``), the runs that hit it by verdict, and the goal."""

    label: str
    hits: int
    passed: int
    failed: int
    errored: int
    target: int
    failing_runs: tuple[int, ...] = ()   # run ids (into CoverageReport.runs) that failed or errored here
    low: float | None = None
    high: float | None = None
    #: Runs that failed while their value was here, for an item sampled at ``end`` (which a failed run
    #: never reaches): a bucket with no hit but these is *not sampled*, not a plain hole.
    failed_here: tuple[int, ...] = ()

    @property
    def covered(self) -> bool:
        return self.hits >= self.target

    @property
    def not_sampled(self) -> bool:
        """No hit, but failing runs were here when they failed (a failing region, not a hole)."""
        return self.hits == 0 and bool(self.failed_here)

    def rerun(self) -> tuple[int, ...]:
        """The runs to rerun for this bucket: its failing runs, else those that failed while here."""
        return self.failing_runs or self.failed_here

    @property
    def runs(self) -> int:
        return self.passed + self.failed + self.errored

    @property
    def pass_rate(self) -> float | None:
        """Passed runs over the runs that hit the bucket, in percent (None when no run did)."""
        total = self.runs
        return None if total == 0 else 100.0 * self.passed / total


@dataclass(frozen=True)
class CrossGrid:
    """A cross of two or more items: its axes; its buckets are the cells, the last axis varying fastest."""

    axes: tuple[str, ...]
    labels: tuple[tuple[str, ...], ...]   # per axis, its bucket labels

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(labels) for labels in self.labels)


@dataclass(frozen=True)
class Extremes:
    """Min / median / max of a record item's numbers, and the run (index) of each extreme."""

    minimum: float
    min_run: int
    median: float
    maximum: float
    max_run: int


@dataclass(frozen=True)
class RecordSummary:
    """A record item's values: count, and its extremes when they are numbers, else its commonest values."""

    count: int
    extremes: Extremes | None = None
    top_values: tuple[tuple[str, int], ...] = ()   # for records that are not numbers


@dataclass(frozen=True)
class ItemResult:
    """One item with its buckets, grade and holes."""

    name: str
    kind: str
    buckets: tuple[BucketResult, ...] = ()
    grade: float | None = None           # None: not graded (records, crosses too big to grid)
    weight: float = 1.0
    at_least: int = 1
    path: str = ""
    unit: str | None = None
    type_text: str | None = None
    text: str | None = None
    event: str | None = None
    ignore: str | None = None
    range: tuple[float, float] | None = None
    every: float | None = None
    samples: int = 0
    runs_sampled: int = 0
    ignored: int = 0
    cross: CrossGrid | None = None
    record: RecordSummary | None = None
    notes: tuple[str, ...] = ()
    #: A cross of two drawn ranges, drawn as a scatter of runs: ``(x, y, verdict, run name)`` per run
    #: (at most :data:`MAX_POINTS`, evenly chosen); empty for every other item.
    points: tuple[tuple[float, float, str, str], ...] = ()
    #: Per axis of a scatter, the declared range and its unit: ``(low, high, unit)``.
    axis_ranges: tuple[tuple[float, float, str], ...] = ()

    @property
    def holes(self) -> tuple[int, ...]:
        """Indices of the buckets below their target (the grade's misses, not-sampled ones included)."""
        return tuple(i for i, b in enumerate(self.buckets) if not b.covered)

    @property
    def plain_holes(self) -> tuple[int, ...]:
        """The holes no run reached, failing or not: where new variants are needed."""
        return tuple(i for i in self.holes if not self.buckets[i].not_sampled)

    @property
    def not_sampled(self) -> tuple[int, ...]:
        """The holes only failing runs reached (their ``end`` never came): failures to fix, not gaps."""
        return tuple(i for i in self.holes if self.buckets[i].not_sampled)

    @property
    def covered_count(self) -> int:
        return sum(1 for b in self.buckets if b.covered)

    @property
    def graded(self) -> bool:
        return self.grade is not None


@dataclass(frozen=True)
class RunTable:
    """Every run of the report, by id: name (the variant to rerun), verdict, reason, folder and log."""

    names: tuple[str, ...]
    verdicts: tuple[str, ...]
    reasons: tuple[str | None, ...]
    folders: tuple[str | None, ...]
    logs: tuple[str | None, ...]
    #: The varied values of each failing run, by run id: an assignment, or (parameter names, values).
    values: Mapping[int, Mapping[str, object] | tuple[tuple[str, ...], Sequence]] = field(default_factory=dict)
    #: The unit of each parameter a sampler drew (its values are shown rounded, with the unit).
    drawn_units: dict[str, str] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.names)

    @functools.cached_property
    def _failing(self) -> tuple[int, ...]:
        ids = [i for i, v in enumerate(self.verdicts) if v in FAILING]
        return tuple(sorted(ids, key=lambda i: [int(p) if p.isdigit() else p
                                                for p in re.split(r"(\d+)", self.names[i])]))

    def failing(self) -> list[int]:
        """Ids of the runs that failed or errored, in the natural order of their names (``x2`` before ``x10``)."""
        return list(self._failing)

    def varied(self, run: int) -> dict[str, object]:
        """A failing run's varied values by parameter ({} for other runs)."""
        values = self.values.get(run)
        if values is None:
            return {}
        if isinstance(values, tuple):
            return dict(zip(values[0], values[1], strict=False))
        return dict(values)

    def values_text(self, run: int) -> str:
        """A failing run's varied values on one line (``speed=84.27kph, road=dry``): keys without their
        scenario, drawn numbers rounded to 4 significant digits with their unit; "" when it has none."""
        parts = []
        for key, value in self.varied(run).items():
            unit = self.drawn_units.get(key)
            shown = drawn_text(value, unit) if unit is not None and isinstance(value, float) else value_label(value)
            parts.append(f"{short_name(key)}={shown}")
        return ", ".join(parts)


@dataclass(frozen=True)
class CoverageReport:
    """The whole report."""

    source: str
    complete: bool
    runs: RunTable
    verdict_counts: dict[str, int]
    items: tuple[ItemResult, ...]
    grade: float | None
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    plan_file: str | None = None
    root: str | None = None
    extra: dict = field(default_factory=dict)
    #: The rounds of a search and its estimate, when the runs are a search's (``scenario_search``).
    search: SearchSection | None = None

    def items_of(self, *kinds: str) -> list[ItemResult]:
        return [item for item in self.items if item.kind in kinds]

    def holes_count(self) -> int:
        """Holes of the items that count in the overall grade (weight above 0)."""
        return sum(len(item.holes) for item in self.items if item.graded and item.weight > 0)
