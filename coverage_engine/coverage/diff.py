"""Two batches compared: what broke, what was fixed, what came and went, and the buckets won and lost.

Each side is its variants' verdicts (one per variant: a repeated variant's pass-rate verdict) and its
coverage report. A variant *regresses* when it passed in A and fails (failed or error) in B; it is
*fixed* the other way round; *new* and *gone* variants are those of one side only. A new failure (a
regression, or a new variant that fails) is what CI gates on. Per coverage item, the buckets covered
in B and not in A are gained, those covered in A and not in B lost.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from coverage_engine.coverage.model import CoverageReport
from coverage_engine.results.files import RESULT_FILE
from coverage_engine.results.read import JunitUnreadable
from coverage_engine.results.verdicts import FAILING, VERDICT_OF_STATE, Verdict, iter_suite_verdicts

#: Names listed per category in the terminal (``--json`` has them all).
SHOWN = 20


@dataclass(frozen=True)
class VariantOutcome:
    """A variant's verdict in one batch, its reason when it did not pass, and whether it is flaky."""

    name: str
    verdict: str
    reason: str | None = None
    flaky: bool = False
    #: How its attempts went (``passed 7 of 10 attempt(s)``), when it was repeated.
    detail: str | None = None

    @property
    def failing(self) -> bool:
        return self.verdict in FAILING


@dataclass(frozen=True)
class Side:
    """One batch to compare: a label, its variants by name, and its coverage."""

    label: str
    outcomes: Mapping[str, VariantOutcome]
    report: CoverageReport


@dataclass(frozen=True)
class ItemChange:
    """The buckets of one coverage item covered on one side only."""

    item: str
    gained: tuple[str, ...]
    lost: tuple[str, ...]


@dataclass(frozen=True)
class BatchDiff:
    """What changed from A to B."""

    a: str
    b: str
    regressions: tuple[VariantOutcome, ...]       # B's outcome
    fixed: tuple[VariantOutcome, ...]
    new: tuple[VariantOutcome, ...]
    gone: tuple[VariantOutcome, ...]             # A's outcome
    flaky: tuple[VariantOutcome, ...]            # flaky in B
    still_failing: int
    items: tuple[ItemChange, ...]
    grades: tuple[float | None, float | None]

    @property
    def new_failures(self) -> tuple[VariantOutcome, ...]:
        """Regressions and new variants that fail: what makes ``diff`` exit 1."""
        return self.regressions + tuple(o for o in self.new if o.failing)


def _covered(report: CoverageReport) -> dict[str, set[str]]:
    return {item.name: {b.label for b in item.buckets if b.covered} for item in report.items if item.buckets}


def _item_changes(a: CoverageReport, b: CoverageReport) -> tuple[ItemChange, ...]:
    before, after = _covered(a), _covered(b)
    changes = []
    for name in list(after) + [n for n in before if n not in after]:
        gained = tuple(sorted(after.get(name, set()) - before.get(name, set())))
        lost = tuple(sorted(before.get(name, set()) - after.get(name, set())))
        if gained or lost:
            changes.append(ItemChange(name, gained, lost))
    return tuple(changes)


def compare(a: Side, b: Side) -> BatchDiff:
    """The differences from ``a`` to ``b`` (names in B's order, gone ones in A's)."""
    regressions, fixed, new = [], [], []
    still = 0
    for name, after in b.outcomes.items():
        before = a.outcomes.get(name)
        if before is None:
            new.append(after)
        elif after.failing and before.verdict == "passed":
            regressions.append(after)
        elif before.failing and after.verdict == "passed":
            fixed.append(before)
        elif before.failing and after.failing:
            still += 1
    gone = tuple(o for name, o in a.outcomes.items() if name not in b.outcomes)
    flaky = tuple(o for o in b.outcomes.values() if o.flaky)
    return BatchDiff(a.label, b.label, tuple(regressions), tuple(fixed), tuple(new), gone, flaky, still,
                     _item_changes(a.report, b.report), (a.report.grade, b.report.grade))


def _names(outcomes: Sequence[VariantOutcome], with_reason: bool = False) -> list[str]:
    lines = []
    for o in outcomes[:SHOWN]:
        reason = f" - {' '.join(o.reason.split())[:200]}" if with_reason and o.reason else ""
        lines.append(f"  {o.name} ({o.verdict}){reason}")
    if len(outcomes) > SHOWN:
        lines.append(f"  ... and {len(outcomes) - SHOWN} more (--json lists all)")
    return lines


def _grade(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f} %"


def diff_lines(d: BatchDiff) -> list[str]:
    """The comparison as the terminal shows it: counts first, then each category's variants."""
    lines = [f"A: {d.a}", f"B: {d.b}",
             f"{len(d.regressions)} regression(s), {len(d.fixed)} fixed, {len(d.new)} new "
             f"({sum(o.failing for o in d.new)} failing), {len(d.gone)} gone, {len(d.flaky)} flaky, "
             f"{d.still_failing} still failing; grade {_grade(d.grades[0])} -> {_grade(d.grades[1])}"]
    for title, outcomes, reason in (("regressions: passed in A, fail in B", d.regressions, True),
                                    ("new failures: not in A, fail in B", [o for o in d.new if o.failing], True),
                                    ("fixed: failed in A, pass in B", d.fixed, False),
                                    ("new", [o for o in d.new if not o.failing], False),
                                    ("gone: in A, not in B", d.gone, False), ("flaky in B", d.flaky, False)):
        if outcomes:
            lines.append(f"{title} ({len(outcomes)}):")
            lines += _names(list(outcomes), reason)
    if d.items:
        lines.append("coverage buckets gained (+) and lost (-):")
        for change in d.items:
            parts = [f"+{label}" for label in change.gained] + [f"-{label}" for label in change.lost]
            shown = ", ".join(parts[:12]) + (f", … {len(parts) - 12} more" if len(parts) > 12 else "")
            lines.append(f"  {change.item}: {shown}")
    return lines


def diff_document(d: BatchDiff) -> dict:
    """The comparison for tools (``diff --json``)."""
    def rows(outcomes: Sequence[VariantOutcome]) -> list[dict]:
        return [{"name": o.name, "verdict": o.verdict, "reason": o.reason, "flaky": o.flaky} for o in outcomes]

    return {"format": "scenario-coverage/diff", "format_version": 1, "a": d.a, "b": d.b,
            "new_failures": len(d.new_failures), "regressions": rows(d.regressions), "fixed": rows(d.fixed),
            "new": rows(d.new), "gone": rows(d.gone), "flaky": rows(d.flaky), "still_failing": d.still_failing,
            "grade": {"a": d.grades[0], "b": d.grades[1]},
            "items": [{"item": c.item, "gained": list(c.gained), "lost": list(c.lost)} for c in d.items]}


def folder_outcomes(path: str | os.PathLike[str]) -> dict[str, VariantOutcome]:
    """The variants of a results folder's merged ``test.xml``: one per testsuite (job, or repeated variant),
    flaky when its ``flaky`` property says so; ``JunitUnreadable`` when there is no readable report."""
    report = os.path.join(os.fspath(path), RESULT_FILE)
    if not os.path.isfile(report):
        raise JunitUnreadable(f"{report}: no merged test.xml (give a batch's results folder)")
    found: dict[str, VariantOutcome] = {}
    for suite in iter_suite_verdicts(report):
        status = VERDICT_OF_STATE.get(suite.properties.get("status", ""))
        verdict: str = suite.verdict
        if verdict is Verdict.PASSED and status in FAILING:
            verdict = status
        props = suite.properties
        detail = f"passed {props['repeat.passed']} of {props['repeat.ran']} attempt(s)" \
            if "repeat.passed" in props and "repeat.ran" in props else None
        found[suite.name] = VariantOutcome(suite.name, verdict, suite.reason or props.get("reason"),
                                           props.get("flaky") == "true", detail)
    return found
