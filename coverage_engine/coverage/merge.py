"""Fold runs into per-item counts: hits, and runs passed / failed / errored per key.

Memory does not grow with the number of samples, only with the number of buckets and of failing runs
(their ids are kept per bucket, to list the variants to rerun) and with ``record`` values (kept for
the median). Runs arrive in chunks (:meth:`CoverageMerger.add_chunk`); inside a chunk, runs that share
their item declarations (``schema_key``) and verdict are processed column by column — one item's
samples of all those runs at once, keyed by its bucketing's ``keys`` and counted by ``Counter`` — so
100,000 runs cost seconds, not minutes. A run with several samples of an item goes the one-run path.

Input coverage comes for free: every key of a run's variant assignment is an item (named
``input:<parameter>``) whose buckets are the values assigned, and every pair of parameters assigned
together is a cross (``input:<a> x <b>``). A parameter value counts as hit by a run that reached a
verdict (passed or failed); runs that errored count against its pass rate but do not hit it, and
skipped or unfinished runs only add their values to the goal.
"""

from __future__ import annotations

from array import array
from collections import Counter, defaultdict
from collections.abc import Hashable, Mapping, Sequence
from operator import itemgetter

from coverage_engine.coverage.buckets import (
    Bucketing,
    ComponentBucketing,
    CrossBuckets,
    DistinctBuckets,
    bucketing_for,
)
from coverage_engine.coverage.input_domains import InputValueBuckets
from coverage_engine.coverage.model import INPUT_ITEM_PREFIX
from coverage_engine.coverage.run_records import ItemDecl
from coverage_engine.coverage.runs import RunInput

#: Index of a verdict in a key's counters ``[hits, passed, failed, errored]``.
SLOTS = {"passed": 1, "failed": 2, "error": 3}

INPUT_PREFIX = INPUT_ITEM_PREFIX

#: A run's varied values as it carries them: its assignment, or its parameter names with their values.
VariedValues = Mapping[str, object] | tuple[tuple[str, ...], Sequence]
CROSS_JOIN = " x "

_FIRST = itemgetter(0)


def input_item_name(parameter: str) -> str:
    return INPUT_PREFIX + parameter


def input_cross_name(first: str, second: str) -> str:
    return f"{INPUT_PREFIX}{first}{CROSS_JOIN}{second}"


def parse_assigned(text: str) -> object:
    """A value read back from text (a JUnit ``variation.*`` property): number, boolean or the text."""
    for convert in (int, float):
        try:
            return convert(text)
        except ValueError:
            pass
    return {"True": True, "False": False, "true": True, "false": False}.get(text, text)


def _varied(run: RunInput) -> VariedValues:
    """A run's varied values, however the run carries them (see :data:`VariedValues`)."""
    if run.parameters and run.values is not None and len(run.values) == len(run.parameters):
        return run.parameters, run.values
    return run.assignment


def _ignored_key(key: Hashable) -> bool:
    return key is None or (type(key) is tuple and None in key)


class ItemCounts:
    """The counts of one item so far; ``kind`` is input, input_cross, cover, cross or record."""

    __slots__ = ("name", "kind", "decl", "bucketing", "stats", "failing", "ignored", "overflow", "samples",
                 "runs_sampled", "limit", "conflicts", "components", "values", "value_runs", "others",
                 "failed_here")

    def __init__(self, name: str, kind: str, decl: ItemDecl | None, bucketing: Bucketing,
                 components: Sequence[ItemCounts] = ()) -> None:
        self.name, self.kind, self.decl, self.bucketing = name, kind, decl, bucketing
        self.stats: dict[Hashable, list[int]] = {}
        self.failing: defaultdict[Hashable, list[int]] = defaultdict(list)
        self.ignored = self.overflow = self.samples = self.runs_sampled = self.conflicts = 0
        self.limit = bucketing.limit if isinstance(bucketing, DistinctBuckets) else 0
        self.components: tuple[ItemCounts, ...] = tuple(components)
        self.values = array("d")           # record items: numeric values …
        self.value_runs = array("q")       # … and the run of each
        self.others: Counter = Counter()   # record items of other types: value counts
        self.failed_here: defaultdict[Hashable, list[int]] = defaultdict(list)   # runs that failed there

    @property
    def plain_bucketing(self) -> ComponentBucketing:
        """The bucketing of an item that is not a cross (a cross's grid is made of its components': the
        resolver lets a cross name plain cover items only)."""
        if isinstance(self.bucketing, CrossBuckets):
            raise TypeError(f"coverage item {self.name} is a cross: it has no buckets of its own")
        return self.bucketing

    @property
    def numeric_record(self) -> bool:
        return self.decl is not None and self.decl.value_type is not None and self.decl.value_type.numeric

    def _row(self, key: Hashable) -> list[int] | None:
        st = self.stats.get(key)
        if st is None:
            if self.limit and len(self.stats) >= self.limit:
                return None
            st = self.stats[key] = [0, 0, 0, 0]
        return st

    # -- many runs with one sample each (the fast path)
    def count_keys(self, keys: list, runs: Sequence[int], slot: int | None, failing: bool, hit: bool = True) -> None:
        """Count one key per run: ``hit`` counts it as a hit; ``slot`` (the runs' verdict) as a run there."""
        left_out: set = set()
        for key, n in Counter(keys).items():
            if _ignored_key(key):
                self.ignored += n
                left_out.add(key)
                continue
            st = self._row(key)
            if st is None:
                self.overflow += n
                self.ignored += n
                left_out.add(key)
                continue
            if hit:
                st[0] += n
            if slot:
                st[slot] += n
        if hit:
            self.samples += len(keys)
            self.runs_sampled += len(keys) - sum(1 for k in keys if k in left_out) if left_out else len(keys)
        if failing:
            lists = self.failing
            if left_out:
                for key, run in zip(keys, runs, strict=True):
                    if key not in left_out:
                        lists[key].append(run)
            else:
                for key, run in zip(keys, runs, strict=True):
                    lists[key].append(run)

    # -- one run, any number of samples
    def add(self, values: Sequence, slot: int | None, failing: bool, run: int) -> None:
        if not values:
            return
        self.samples += len(values)
        hit: set = set()
        for key in self.bucketing.keys(list(values)):
            if _ignored_key(key):
                self.ignored += 1
                continue
            st = self._row(key)
            if st is None:
                self.overflow += 1
                self.ignored += 1
                continue
            st[0] += 1
            hit.add(key)
        if hit:
            self.runs_sampled += 1
            for key in hit:
                if slot:
                    self.stats[key][slot] += 1
                if failing:
                    self.failing[key].append(run)

    # -- a failed run's values of items whose event never came: not hits, but where it failed
    def note_failure(self, values: Sequence, run: int) -> None:
        try:
            keys = self.bucketing.keys(list(values))
        except (TypeError, ValueError):
            return
        for key in set(keys):
            if not _ignored_key(key) and self._row(key) is not None:
                self.failed_here[key].append(run)

    # -- record items: raw values with their runs
    def add_records(self, values: list, runs: list[int]) -> None:
        if not values:
            return
        self.samples += len(values)
        self.runs_sampled += len(set(runs))
        if self.numeric_record:
            self.values.extend(values)
            self.value_runs.extend(runs)
        else:
            self.others.update(values)

    # -- varied parameters: one value per run; only a run with a verdict hits it
    def add_inputs(self, values: list, runs: Sequence[int], slot: int | None) -> None:
        if slot is None:
            for value in set(values):
                self._row(value)
            return
        self.count_keys(values, runs, slot, failing=slot != 1, hit=slot != 3)


class _InputPlan:
    __slots__ = ("items", "crosses", "getter")

    def __init__(self, keys: tuple[str, ...], items: list[ItemCounts],
                 crosses: list[tuple[ItemCounts, int, int]]) -> None:
        self.items, self.crosses = items, crosses
        self.getter = itemgetter(*keys) if len(keys) > 1 else (lambda a, _k=keys[0]: (a[_k],))


class CoverageMerger:
    """Reads :class:`RunInput` records in chunks; :mod:`grading` turns the result into the report."""

    def __init__(self) -> None:
        self.run_names: list[str] = []
        self.run_verdicts: list[str] = []
        self.run_reasons: list[str | None] = []
        self.run_folders: list[str | None] = []
        self.run_logs: list[str | None] = []
        self.items: dict[str, ItemCounts] = {}
        #: The varied values of each run that failed or errored (by run id), for the failing-runs tables:
        #: a reference to what the run carries (its assignment, or its parameter names and values), no copy.
        self.failing_values: dict[int, VariedValues] = {}
        self.warnings: list[str] = []
        self._schemas: dict[Hashable, list[ItemCounts | None]] = {}
        self._inputs: dict[tuple[str, ...], _InputPlan] = {}
        self._malformed = 0

    def add(self, run: RunInput) -> None:
        self.add_chunk([run])

    # ------------------------------------------------------------------ a chunk of runs
    def add_chunk(self, runs: Sequence[RunInput]) -> None:
        base = len(self.run_names)
        self.run_names.extend(r.name for r in runs)
        self.run_verdicts.extend(r.verdict for r in runs)
        self.run_reasons.extend(r.reason for r in runs)
        self.run_folders.extend(r.folder for r in runs)
        self.run_logs.extend(r.log for r in runs)
        inputs: dict[tuple, list[int]] = {}
        schemas: dict[tuple, list[int]] = {}
        for i, run in enumerate(runs):
            slot = SLOTS.get(run.verdict)
            if slot == 2 or slot == 3:
                self.failing_values[base + i] = _varied(run)
            if run.parameters:
                inputs.setdefault((run.parameters, slot, True), []).append(i)
            elif run.assignment:
                inputs.setdefault((tuple(run.assignment), slot, False), []).append(i)
            if run.items and (slot is not None or run.verdict == "skipped"):   # a pending run's samples are not final
                key = run.schema_key if run.schema_key is not None else tuple(run.items)
                schemas.setdefault((key, slot, run.single is not None), []).append(i)
        for (keys, slot, listed), members in inputs.items():
            plan = self._inputs.get(keys) or self._input_plan(keys)
            if listed:
                rows = [runs[i].values for i in members]
                if any(row is None or len(row) != len(keys) for row in rows):
                    self._malformed += len(rows)
                    continue
            else:
                rows = list(map(plan.getter, [runs[i].assignment for i in members]))
            self._add_inputs(plan, slot, rows, [base + i for i in members])
        for (key, slot, _single), members in schemas.items():
            group = [runs[i] for i in members]
            targets = self._schemas.get(key)
            if targets is None:
                targets = self._schemas[key] = self._match(group[0].items, group[0].name)
            self._add_samples(targets, group, slot, [base + i for i in members])
            if slot == 2 or slot == 3:
                for i in members:
                    if runs[i].unsampled:
                        self._add_unsampled(targets, runs[i].unsampled, base + i)

    @staticmethod
    def _add_unsampled(targets: list[ItemCounts | None], unsampled: Sequence[list], run: int) -> None:
        """Where a failing run was when it failed, for the items whose event never came."""
        for counts, values in zip(targets, unsampled, strict=False):
            if counts is not None and values and counts.kind != "record":
                counts.note_failure(values, run)

    @staticmethod
    def _add_inputs(plan: _InputPlan, slot: int | None, rows: list, rids: list[int]) -> None:
        columns = list(zip(*rows, strict=True))
        for counts, column in zip(plan.items, columns, strict=True):
            counts.add_inputs(list(column), rids, slot)
        for counts, i, j in plan.crosses:
            if slot is not None:
                counts.add_inputs(list(zip(columns[i], columns[j], strict=True)), rids, slot)

    def _add_samples(self, targets: list[ItemCounts | None], group: list[RunInput], slot: int | None,
                     rids: list[int]) -> None:
        width = len(targets)
        single = group[0].single is not None       # a group is all one encoding (see add_chunk)
        good = [k for k, run in enumerate(group) if len((run.single or ()) if single else run.samples) == width]
        if len(good) != len(group):
            self._malformed += len(group) - len(good)
            group, rids = [group[k] for k in good], [rids[k] for k in good]
        if not group:
            return
        failing = slot == 2 or slot == 3
        if single:
            columns = list(zip(*(run.single for run in group), strict=True))
        else:
            columns = list(zip(*(run.samples for run in group), strict=True))
        ignored = [run.ignored for run in group if run.ignored and any(run.ignored)]
        for j, counts in enumerate(targets):
            if counts is None:
                continue
            for dropped in ignored:
                if j < len(dropped):
                    counts.ignored += dropped[j]
            column = columns[j]
            try:
                if single:
                    self._add_values(counts, list(column), rids, slot, failing)
                else:
                    self._add_column(counts, column, rids, slot, failing)
            except (TypeError, ValueError):
                nested = tuple([value] for value in column) if single else column
                self._one_by_one(counts, nested, rids, slot, failing)

    @staticmethod
    def _add_values(counts: ItemCounts, values: list, rids: list[int], slot: int | None, failing: bool) -> None:
        """One sample per run: ``values[k]`` of run ``rids[k]``."""
        if counts.kind == "record":
            counts.add_records(values, rids)
        else:
            counts.count_keys(counts.bucketing.keys(values), rids, slot, failing)

    @classmethod
    def _add_column(cls, counts: ItemCounts, column: tuple, rids: list[int], slot: int | None, failing: bool) -> None:
        if set(map(len, column)) == {1}:
            cls._add_values(counts, list(map(_FIRST, column)), rids, slot, failing)
            return
        if counts.kind == "record":
            values, runs = [], []
            for samples, run in zip(column, rids, strict=True):
                values.extend(samples)
                runs.extend([run] * len(samples))
            counts.add_records(values, runs)
            return
        for samples, run in zip(column, rids, strict=True):
            counts.add(samples, slot, failing, run)

    def _one_by_one(self, counts: ItemCounts, column: tuple, rids: list[int], slot: int | None,
                    failing: bool) -> None:
        """The fallback when a column holds values its bucketing cannot take: each run on its own."""
        for samples, run in zip(column, rids, strict=True):
            try:
                if counts.kind == "record":
                    counts.add_records(list(samples), [run] * len(samples))
                else:
                    counts.add(samples, slot, failing, run)
            except (TypeError, ValueError):
                self._malformed += 1

    def finish_warnings(self) -> list[str]:
        """Warnings of the whole merge (call after the last chunk)."""
        out = list(self.warnings)
        if self._malformed:
            out.append(f"{self._malformed} run(s) or sample(s) did not match their item declarations and "
                       f"were left out")
        return out

    # ------------------------------------------------------------------ matching declarations to items
    def _input_plan(self, keys: tuple[str, ...]) -> _InputPlan:
        items = []
        for key in keys:
            name = input_item_name(key)
            counts = self.items.get(name)
            if counts is None:
                counts = self.items[name] = ItemCounts(name, "input", None, InputValueBuckets())
            items.append(counts)
        crosses = []
        for i in range(len(keys)):
            for j in range(i + 1, len(keys)):
                name = input_cross_name(keys[i], keys[j])
                counts = self.items.get(name)
                if counts is None:
                    bucketing = CrossBuckets((items[i].plain_bucketing, items[j].plain_bucketing))
                    counts = self.items[name] = ItemCounts(name, "input_cross", None, bucketing,
                                                           (items[i], items[j]))
                crosses.append((counts, i, j))
        plan = self._inputs[keys] = _InputPlan(keys, items, crosses)
        return plan

    def _match(self, decls: Sequence[ItemDecl], run_name: str) -> list[ItemCounts | None]:
        """The merge's item for each declaration of a run (created on first sight); None where it conflicts."""
        out: list[ItemCounts | None] = []
        for decl in decls:
            name = decl.full_name
            counts = self.items.get(name)
            if counts is None:
                counts = self._create(decl, decls)
                if counts is None:
                    self.warnings.append(f"{name}: a component of the cross is missing or conflicting in run "
                                         f"{run_name}; its samples there are left out")
                    out.append(None)
                    continue
                self.items[name] = counts
            elif counts.decl is None or counts.decl.signature() != decl.signature():
                counts.conflicts += 1
                if counts.conflicts == 1:
                    self.warnings.append(f"{name}: run {run_name} declares it differently from the first run "
                                         f"that has it (type, unit, range, every or items); its samples there "
                                         f"are left out")
                out.append(None)
                continue
            out.append(counts)
        return out

    def _create(self, decl: ItemDecl, decls: Sequence[ItemDecl]) -> ItemCounts | None:
        if decl.kind == "record":
            return ItemCounts(decl.full_name, "record", decl, DistinctBuckets())
        if not decl.is_cross:
            assert decl.value_type is not None
            return ItemCounts(decl.full_name, "cover", decl, bucketing_for(decl.value_type, decl.range, decl.every))
        components = []
        for part in decl.items:
            target = next((d for d in decls if d.path == decl.path and d.name == part), None)
            if target is None:
                return None
            counts = self.items.get(target.full_name)
            if counts is None:
                counts = self._create(target, decls)
                if counts is None:
                    return None
                self.items[target.full_name] = counts
            elif counts.decl is None or counts.decl.signature() != target.signature():
                return None
            components.append(counts)
        return ItemCounts(decl.full_name, "cross", decl, CrossBuckets([c.plain_bucketing for c in components]), components)
