"""What people read while ``scenario_variation`` works: what is varied, what does not resolve, progress.

Messages go to stdout, problems to stderr, both plain text. Only the progress of a long generation
(:data:`RICH_PROGRESS_FROM` variants or more) is a rich bar, and only where
:func:`executor.output.terminal.wants_rich` allows it; elsewhere a plain line every few seconds.
"""

from __future__ import annotations

import math
import sys
import time
from typing import TYPE_CHECKING

from coverage_engine.printable import printable_lines
from executor.output.terminal import wants_rich

if TYPE_CHECKING:
    from coverage_engine.variation.plan import ParsedVariation, VariationPlan

#: Variants from which a terminal gets a rich progress bar.
RICH_PROGRESS_FROM = 2000


def echo(message: str = "", err: bool = False) -> None:
    """One line on stdout (``err``: stderr), flushed so it interleaves with the other stream; names and
    values in it came from files, so control characters are escaped (:func:`printable_lines`)."""
    print(printable_lines(message), file=sys.stderr if err else sys.stdout, flush=True)


def size_text(n: float) -> str:
    """``700 bytes``, ``68 MB``: for disk-space estimates."""
    for unit in ("bytes", "KB", "MB", "GB", "TB", "PB"):
        if n < 1024:
            return f"{n:.0f} {unit}"
        n /= 1024
    return f"{n:.3g} EB"


def duration_text(seconds: float) -> str:
    """``42 s``, ``3 min 20 s``, ``5 h 02 min``, ``12 days``, ``3.2e+07 years``: for ETAs."""
    if seconds < 60:
        return f"{seconds:.0f} s"
    if seconds < 3600:
        return f"{seconds // 60:.0f} min {seconds % 60:02.0f} s"
    if seconds < 86400 * 2:
        return f"{seconds // 3600:.0f} h {seconds % 3600 // 60:02.0f} min"
    if seconds < 86400 * 365 * 2:
        return f"{seconds / 86400:.0f} days"
    return f"{seconds / (86400 * 365.25):.3g} years"


def slot_sizes(plan: ParsedVariation) -> str:
    """Choices per independent slot, ``8 x 8 x 8`` (keeps on the same parameter count as one)."""
    return " x ".join(str(slot.count) for slot in plan.slots)


def _space(plan: VariationPlan) -> str:
    """What a strategy chose from: ``8 x 8 x 8 values``, or with drawn ranges ``400 points drawn in 2
    range(s) x 7 x 3 values`` (a drawn range has as many values as points; their product means nothing)."""
    drawn = [slot for slot in plan.slots
             if any(d < len(plan.dimensions) and plan.dimensions[d].continuous is not None for d in slot.dims)]
    if not drawn:
        return f"{slot_sizes(plan)} values"
    listed = " x ".join(str(slot.count) for slot in plan.slots if slot not in drawn)
    points = f"{len(plan.dimensions[drawn[0].dims[0]].choices)} points drawn in {len(drawn)} range(s)"
    return f"{points} x {listed} values" if listed else points


#: Values of a dimension shown one by one; a longer dimension shows its first and last ones.
SHOW_VALUES_UP_TO = 20


def describe(plan: VariationPlan) -> None:
    """Say what will be varied (or that nothing is)."""
    if not plan.dimensions and plan.documents is None:
        echo(f"{plan.path}: no keep(... in [...]) constraint: exactly one concrete model")
        return
    first_of = {}
    for slot in plan.slots:
        for later in slot.dims[1:]:
            first_of[later] = slot.dims[0]
    for i, dim in enumerate(plan.dimensions):
        if dim.continuous is not None:
            spec = dim.continuous
            echo(f"{dim.location}: {dim.key}: range [{spec.text(spec.low)}..{spec.text(spec.high)}], "
                 f"{len(dim.choices)} value(s) drawn")
            continue
        texts = [c.text for c in dim.choices]
        if len(texts) > SHOW_VALUES_UP_TO:        # a range [1..6000] is not worth 6000 numbers on the terminal
            texts = [*texts[:SHOW_VALUES_UP_TO - 3], "…", *texts[-2:]]
        values = ", ".join(texts)
        joint = ""
        if i in first_of:
            other = plan.dimensions[first_of[i]]
            joint = f" (the same parameter as line {other.location.line}: checked together, one dimension)"
        echo(f"{dim.location}: {dim.key}: {len(dim.choices)} values [{values}]{joint}")
    if plan.documents is not None:
        echo(f"parameter file: {len(plan.documents)} documents")
    if plan.constraints is not None:
        keys = plan.keys
        for condition in plan.constraints.conditions:
            names = ", ".join(keys[a] for a in condition.axes) or "no varied parameter"
            if condition.per_row:
                ruled = f"{plan.excluded_by.get(condition.text, 0)} drawn variant(s) break it"
            else:
                table = math.prod(plan.sizes[a] for a in condition.axes)
                ruled = f"rules out {len(condition.forbidden)} of {table} value combination(s) of {names}"
            echo(f"{condition.location}: condition {condition.text}: {ruled} (never written)")
    product = math.prod(plan.sizes)
    if plan.rows is not None and not (plan.excluded and plan.total + plan.excluded == product):
        excluded = f" ({plan.excluded} drawn broke a keep condition)" if plan.excluded else ""
        echo(f"{plan.total} variants chosen from {_space(plan)}{excluded}, {plan.resolutions} "
             "resolutions to check the values")
        return
    excluded = f"; {plan.excluded} break a keep condition" if plan.excluded else ""
    echo(f"{plan.total} combinations ({slot_sizes(plan)}{excluded}), {plan.resolutions} resolutions to check "
         "the values")


def report_rejections(plan: VariationPlan) -> None:
    """Each value that does not resolve: where it is written (the line as the user wrote it, a caret under
    the value), why (the resolver's message), and how many combinations hold it."""
    lines = plan.text.splitlines()
    for rejection in plan.rejections:
        values = ", ".join(f"{k} = {v}" for k, v in rejection.shown.items())
        where = f"{rejection.location}: " if rejection.location is not None else f"{plan.path}: "
        echo(f"{where}error: {values} does not resolve: {rejection.error.message} "
             f"({rejection.skipped} combination(s) hold it)", err=True)
        location = rejection.location
        if location is not None and 1 <= location.line <= len(lines):
            echo("    " + lines[location.line - 1].strip("\n"), err=True)
            echo("    " + " " * (location.column - 1) + "^", err=True)


def list_assignments(plan: VariationPlan) -> int:
    """``--list``: one line per combination; exit code 1 when some do not resolve."""
    stem = plan.path.stem
    skipped = 0
    for index, choices, rejection in plan.combinations():
        assignment = ", ".join(f"{k} = {v}" for k, v in plan.shown_assignment(choices).items())
        if rejection is None:
            echo(f"{stem}{index}: {assignment or '(no varied parameter)'}")
        else:
            skipped += 1
            echo(f"{stem}{index}: {assignment} (skipped: does not resolve)")
    echo(f"{plan.total - skipped} variants would be generated" + (f", {skipped} skipped" if skipped else ""))
    return 1 if skipped else 0


class Ticker:
    """Progress of a long computation before anything is written (a covering array): a plain line on
    stderr every :data:`Progress.PLAIN_EVERY` seconds, nothing when it is quick."""

    def __init__(self, what: str) -> None:
        self.what = what
        self._started = time.monotonic()
        self._next = self._started + Progress.PLAIN_EVERY

    def __call__(self, done: int, total: int) -> None:
        now = time.monotonic()
        if now < self._next or not total:
            return
        self._next = now + Progress.PLAIN_EVERY
        echo(f"... {self.what}: {done * 100 / total:.0f} % after {duration_text(now - self._started)}", err=True)


class Progress:
    """A rich progress bar on a terminal for long generations; elsewhere a plain line every few seconds."""

    #: Seconds between two plain progress lines.
    PLAIN_EVERY = 5.0

    def __init__(self, total: int) -> None:
        self.total = total
        self.done = 0
        self._rich = None
        self._started = time.monotonic()
        self._next_plain = self._started + self.PLAIN_EVERY
        if total >= RICH_PROGRESS_FROM and wants_rich(sys.stderr):
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._rich = Progress("writing", BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                                  TimeRemainingColumn(), console=Console(stderr=True), transient=True)
            self._task = self._rich.add_task("variants", total=total)
            self._rich.start()

    def advance(self) -> None:
        """One more combination handled (written or skipped)."""
        self.done += 1
        if self.done & 255 and self.done != self.total:
            return
        if self._rich is not None:
            self._rich.update(self._task, completed=self.done)
            return
        now = time.monotonic()
        if now >= self._next_plain and self.done != self.total:
            self._next_plain = now + self.PLAIN_EVERY
            rate = self.done / max(now - self._started, 1e-9)
            echo(f"... {self.done} of {self.total} combinations ({self.done * 100 / self.total:.2g} %), "
                 f"{rate:,.0f}/s, about {duration_text((self.total - self.done) / rate)} left")

    def close(self) -> None:
        """Release the terminal (the rich bar is transient)."""
        if self._rich is not None:
            self._rich.stop()
