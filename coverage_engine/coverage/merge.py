"""Fold runs, one at a time, into per-item counts: hits, and runs passed / failed / errored per key.

Memory does not grow with the number of samples, only with the number of buckets and of failing runs
(their ids are kept per bucket, to list the variants to rerun) and with ``record`` values (kept for
the median). The item declarations of a run are matched to the merge's items once per distinct set
of declarations (``schema_key``), so 100,000 runs of one scenario pay for it once.

Input coverage comes for free: every key of a run's variant assignment is an item (named
``input:<parameter>``) whose buckets are the values assigned, and every pair of parameters assigned
together is a cross (``input:<a> x <b>``). A parameter value counts as hit by a run that reached a
verdict (passed or failed); runs that errored count against its pass rate but do not hit it, and
skipped or unfinished runs only add their values to the goal.
"""

from __future__ import annotations

from array import array
from collections import Counter
from collections.abc import Hashable, Sequence

from coverage_engine.coverage.buckets import (
    CrossBuckets,
    DistinctBuckets,
    InputValueBuckets,
    bucketing_for,
)
from coverage_engine.coverage.run_file import ItemDecl
from coverage_engine.coverage.runs import RunInput

#: Index of a verdict in a key's counters ``[hits, passed, failed, errored]``.
SLOTS = {"passed": 1, "failed": 2, "error": 3}

INPUT_PREFIX = "input:"
CROSS_JOIN = " x "


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


class ItemCounts:
    """The counts of one item so far; ``kind`` is input, input_cross, cover, cross or record."""

    __slots__ = ("name", "kind", "decl", "bucketing", "stats", "failing", "ignored", "overflow", "samples",
                 "runs_sampled", "limit", "conflicts", "components", "values", "value_runs", "others")

    def __init__(self, name: str, kind: str, decl: ItemDecl | None, bucketing, components=()) -> None:
        self.name, self.kind, self.decl, self.bucketing = name, kind, decl, bucketing
        self.stats: dict[Hashable, list[int]] = {}
        self.failing: dict[Hashable, list[int]] = {}
        self.ignored = self.overflow = self.samples = self.runs_sampled = self.conflicts = 0
        self.limit = bucketing.limit if isinstance(bucketing, DistinctBuckets) else 0
        self.components: tuple[ItemCounts, ...] = tuple(components)
        self.values = array("d")           # record items: numeric values …
        self.value_runs = array("q")       # … and the run of each
        self.others: Counter = Counter()   # record items of other types: value counts

    # -- cover items and crosses: every sample is a hit; the run counts once per key it hit
    def add(self, values: Sequence, slot: int | None, failing: bool, run: int) -> None:
        if not values:
            return
        key, stats = self.bucketing.key, self.stats
        self.samples += len(values)
        if len(values) == 1:
            k = key(values[0])
            if k is None:
                self.ignored += 1
                return
            st = stats.get(k)
            if st is None:
                if self.limit and len(stats) >= self.limit:
                    self.overflow += 1
                    self.ignored += 1
                    return
                st = stats[k] = [0, 0, 0, 0]
            st[0] += 1
            self.runs_sampled += 1
            if slot:
                st[slot] += 1
            if failing:
                self.failing.setdefault(k, []).append(run)
            return
        hit: set = set()
        for value in values:
            k = key(value)
            if k is None:
                self.ignored += 1
                continue
            st = stats.get(k)
            if st is None:
                if self.limit and len(stats) >= self.limit:
                    self.overflow += 1
                    self.ignored += 1
                    continue
                st = stats[k] = [0, 0, 0, 0]
            st[0] += 1
            hit.add(k)
        if hit:
            self.runs_sampled += 1
            for k in hit:
                if slot:
                    stats[k][slot] += 1
                if failing:
                    self.failing.setdefault(k, []).append(run)

    # -- varied parameters: one value per run; only a run with a verdict hits it
    def add_input(self, value: Hashable, slot: int | None, failing: bool, run: int) -> None:
        st = self.stats.get(value)
        if st is None:
            st = self.stats[value] = [0, 0, 0, 0]
        if slot is None:
            return
        if slot != 3:
            st[0] += 1
            self.runs_sampled += 1
        st[slot] += 1
        if failing:
            self.failing.setdefault(value, []).append(run)

    # -- record items: raw values with their runs
    def add_record(self, values: Sequence, run: int) -> None:
        if not values:
            return
        self.samples += len(values)
        self.runs_sampled += 1
        if self.decl is not None and self.decl.value_type is not None and self.decl.value_type.numeric:
            self.values.extend(values)
            self.value_runs.extend([run] * len(values))
        else:
            self.others.update(values)


class _InputPlan:
    __slots__ = ("items", "crosses")

    def __init__(self, items: list[ItemCounts], crosses: list[tuple[ItemCounts, int, int]]) -> None:
        self.items, self.crosses = items, crosses


class CoverageMerger:
    """Reads :class:`RunInput` records one by one; :mod:`grading` turns the result into the report."""

    def __init__(self) -> None:
        self.run_names: list[str] = []
        self.run_verdicts: list[str] = []
        self.run_reasons: list[str | None] = []
        self.run_folders: list[str | None] = []
        self.run_logs: list[str | None] = []
        self.items: dict[str, ItemCounts] = {}
        self.warnings: list[str] = []
        self._schemas: dict[Hashable, list[ItemCounts | None]] = {}
        self._inputs: dict[tuple[str, ...], _InputPlan] = {}

    # ------------------------------------------------------------------ one run
    def add(self, run: RunInput) -> None:
        rid = len(self.run_names)
        self.run_names.append(run.name)
        self.run_verdicts.append(run.verdict)
        self.run_reasons.append(run.reason)
        self.run_folders.append(run.folder)
        self.run_logs.append(run.log)
        slot = SLOTS.get(run.verdict)
        failing = slot == 2 or slot == 3
        assignment = run.assignment
        if assignment:
            keys = tuple(assignment)
            plan = self._inputs.get(keys)
            if plan is None:
                plan = self._input_plan(keys)
            values = [assignment[k] for k in keys]
            for counts, value in zip(plan.items, values):  # noqa: B905 - same length by construction
                counts.add_input(value, slot, failing, rid)
            for counts, i, j in plan.crosses:
                counts.add_input((values[i], values[j]), slot, failing, rid)
        if run.items:
            if slot is None and run.verdict != "skipped":
                return  # a pending run's samples are not final
            key = run.schema_key if run.schema_key is not None else tuple(run.items)
            targets = self._schemas.get(key)
            if targets is None:
                targets = self._schemas[key] = self._match(run.items, run.name)
            for counts, values, dropped in zip(targets, run.samples, run.ignored or [0] * len(targets)):  # noqa: B905
                if counts is None:
                    continue
                if dropped:
                    counts.ignored += dropped
                if counts.kind == "record":
                    counts.add_record(values, rid)
                else:
                    counts.add(values, slot, failing, rid)

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
                    bucketing = CrossBuckets((items[i].bucketing, items[j].bucketing))
                    counts = self.items[name] = ItemCounts(name, "input_cross", None, bucketing,
                                                           (items[i], items[j]))
                crosses.append((counts, i, j))
        plan = self._inputs[keys] = _InputPlan(items, crosses)
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
        return ItemCounts(decl.full_name, "cross", decl, CrossBuckets([c.bucketing for c in components]), components)
