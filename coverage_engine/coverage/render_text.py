"""The report for a terminal: rich tables and bars; plain ASCII when the output is not a terminal.

Long lists are cut (buckets per item, names per bucket, failing runs) with a count of what was left
out; ``json`` and ``html`` have everything.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from rich import box
from rich.console import Console, Group, JustifyMethod
from rich.table import Table
from rich.text import Text

from coverage_engine.coverage.model import KIND_TITLES, BucketResult, CoverageReport, ItemResult, short_name
from coverage_engine.printable import printable

MAX_BUCKET_ROWS = 40
MAX_GRID_COLUMNS = 12
MAX_GRID_ROWS = 40
MAX_NAMES = 5
MAX_HOLES = 20
MAX_FAILING_RUNS = 50
MAX_REASON_CHARS = 160
BAR_WIDTH = 20

#: The columns of the tables, with how each is aligned.
Columns = tuple[tuple[str, JustifyMethod], ...]
_OVERVIEW_COLUMNS: Columns = (("item", "left"), ("kind", "left"), ("buckets", "right"), ("holes", "right"),
                              ("weight", "right"), ("grade", "right"), ("", "left"))
_BUCKET_COLUMNS: Columns = (("bucket", "left"), ("hits", "right"), ("runs", "right"), ("pass rate", "right"),
                            ("", "left"), ("failing runs (rerun)", "left"))
_RECORD_COLUMNS: Columns = (("item", "left"), ("unit", "left"), ("samples", "right"), ("min", "right"),
                            ("min run", "left"), ("median", "right"), ("max", "right"), ("max run", "left"))


#: Values with no text in them (left as they are: a report's run ids and counts are most of its values).
_NO_TEXT = (int, float, bool, type(None))


def escaped(value: Any) -> Any:
    """``value`` (the report, or any part of it) with every string in it made :func:`printable`."""
    kind = type(value)
    if kind is str:
        return printable(value)
    if kind in _NO_TEXT:
        return value
    if kind is tuple or kind is list:
        if all(type(part) in _NO_TEXT for part in value):
            return value
        if all(type(part) is str for part in value):
            parts = list(map(printable, value))
        else:
            parts = [escaped(part) for part in value]
        return tuple(parts) if kind is tuple else parts
    if isinstance(value, dict):
        return {escaped(key): escaped(part) for key, part in value.items()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return dataclasses.replace(value, **{f.name: escaped(getattr(value, f.name))
                                             for f in dataclasses.fields(value) if f.init})
    return value


def percent(value: float | None) -> str:
    return "—" if value is None else f"{value:.1f} %"


class _Style:
    def __init__(self, plain: bool) -> None:
        self.plain = plain
        self.box = None if plain else box.SIMPLE_HEAD
        self.full, self.empty = ("#", ".") if plain else ("█", "░")

    def bar(self, fraction: float, width: int = BAR_WIDTH, colour: str = "green") -> Text:
        fraction = min(max(fraction, 0.0), 1.0)
        filled = round(fraction * width)
        text = Text(self.full * filled, style="" if self.plain else colour)
        text.append(self.empty * (width - filled), style="" if self.plain else "grey37")
        return text

    def grade_colour(self, grade: float | None) -> str:
        if grade is None:
            return "grey50"
        return "green" if grade >= 90 else "yellow" if grade >= 60 else "red"

    def styled(self, text: str, style: str) -> Text:
        return Text(text, style="" if self.plain else style)


def _names(bucket: BucketResult, names: tuple[str, ...]) -> str:
    runs = bucket.rerun()
    shown = ", ".join(names[i] for i in runs[:MAX_NAMES])
    return shown + (f" +{len(runs) - MAX_NAMES} more" if len(runs) > MAX_NAMES else "")


def _summary(report: CoverageReport, style: _Style) -> list:
    counts = report.verdict_counts
    parts = [f"{n} {v}" for v, n in counts.items() if n]
    head = Text()
    head.append("Scenario coverage", style=None if style.plain else "bold")
    head.append(f" of {report.source}: {len(report.runs)} run(s)" + (f" ({', '.join(parts)})" if parts else ""))
    if report.complete:
        head.append("  [complete]", style=None if style.plain else "green")
    else:
        head.append("\nINCOMPLETE: the batch is still running or was stopped; the finished runs are covered",
                    style=None if style.plain else "bold yellow")
    grade = Text("Overall grade ")
    grade.append(percent(report.grade), style=None if style.plain else f"bold {style.grade_colour(report.grade)}")
    grade.append("  ")
    grade.append(style.bar((report.grade or 0) / 100, 30, style.grade_colour(report.grade)))
    graded = [i for i in report.items if i.graded]
    grade.append(f"  {len(graded)} graded item(s), {report.holes_count()} hole(s)")
    if report.plan_file:
        grade.append(f", plan {report.plan_file}")
    out: list = [head, grade]
    for note in report.notes:
        out.append(style.styled(f"note: {note}", "yellow"))
    for warning in report.warnings:
        out.append(style.styled(f"warning: {warning}", "yellow"))
    return out


def _overview(report: CoverageReport, style: _Style) -> Table:
    table = Table(title="Items", box=style.box, title_justify="left", expand=False)
    for column, justify in _OVERVIEW_COLUMNS:
        table.add_column(column, justify=justify, no_wrap=column == "item")
    for item in report.items:
        if not item.graded:
            continue
        table.add_row(item.name, KIND_TITLES[item.kind], f"{item.covered_count}/{len(item.buckets)}",
                      str(len(item.holes)), f"{item.weight:g}",
                      style.styled(percent(item.grade), style.grade_colour(item.grade)),
                      style.bar((item.grade or 0) / 100, colour=style.grade_colour(item.grade)))
    return table


def _describe(item: ItemResult) -> str:
    facts = [KIND_TITLES[item.kind]]
    if item.type_text:
        facts.append(item.type_text)
    if item.unit:
        facts.append(f"in {item.unit}")
    if item.range:
        facts.append(f"range [{item.range[0]:g}..{item.range[1]:g}]" + (f" every {item.every:g}" if item.every else ""))
    if item.event and item.event != "end":
        facts.append(f"sampled at {item.event}")
    if item.ignore:
        facts.append(f"ignore: {item.ignore}")
    if item.at_least > 1:
        facts.append(f"at least {item.at_least} hits per bucket")
    if item.ignored:
        facts.append(f"{item.ignored} sample(s) ignored")
    return ", ".join(facts)


def _title(item: ItemResult, style: _Style) -> Text:
    title = Text()
    title.append(item.name, style=None if style.plain else "bold cyan")
    if item.graded:
        title.append("  grade ")
        title.append(percent(item.grade), style=None if style.plain else f"bold {style.grade_colour(item.grade)}")
        title.append(f" ({item.covered_count} of {len(item.buckets)} buckets)")
    title.append(f"  — {_describe(item)}")
    if item.text:
        title.append(f"\n  {item.text}", style=None if style.plain else "italic")
    return title


def _bucket_table(item: ItemResult, names: tuple[str, ...], style: _Style) -> Table:
    table = Table(box=style.box, expand=False)
    for column, justify in _BUCKET_COLUMNS:
        table.add_column(column, justify=justify)
    peak = max((b.hits for b in item.buckets), default=0) or 1
    for bucket in item.buckets[:MAX_BUCKET_ROWS]:
        if bucket.covered:
            rate = bucket.pass_rate
            colour = "green" if rate is None or rate >= 99.5 else "yellow" if rate >= 50 else "red"
            bar = style.bar(bucket.hits / peak, 16, colour)
        elif bucket.not_sampled:
            bar = style.styled(f"not sampled: {len(bucket.failed_here)} failed run(s) were here", "bold yellow")
        else:
            bar = style.styled("hole" if bucket.hits == 0 else f"below {item.at_least}", "bold red")
        table.add_row(bucket.label, str(bucket.hits), str(bucket.runs), percent(bucket.pass_rate), bar,
                      _names(bucket, names))
    if len(item.buckets) > MAX_BUCKET_ROWS:
        table.add_row(f"… {len(item.buckets) - MAX_BUCKET_ROWS} more", "", "", "", "", "")
    return table


def _grid(item: ItemResult, style: _Style) -> tuple[Text, Table] | None:
    """A two-way cross as a table of cells, with a caption naming its axes (None when it is not drawn)."""
    grid = item.cross
    if grid is None or len(grid.labels) != 2:
        return None
    rows, columns = grid.labels
    if len(columns) > MAX_GRID_COLUMNS or len(rows) > MAX_GRID_ROWS:
        return None
    table = Table(box=style.box, expand=False)
    table.add_column(axes_title(grid.axes), no_wrap=True)
    for label in columns:
        table.add_column(label, justify="right")
    for r, label in enumerate(rows):
        cells: list = [label]
        for c in range(len(columns)):
            bucket = item.buckets[r * len(columns) + c]
            if bucket.not_sampled:
                cells.append(style.styled(f"{len(bucket.failed_here)} failed", "yellow"))
                continue
            if bucket.hits == 0:
                cells.append(style.styled("·" if not style.plain else ".", "red"))
                continue
            rate = bucket.pass_rate
            text = f"{bucket.hits}" + ("" if rate is None else f" ({rate:.0f}%)")
            colour = "green" if rate is None or rate >= 99.5 else "yellow" if rate >= 50 else "red"
            cells.append(style.styled(text, colour if bucket.covered else "red"))
        table.add_row(*cells)
    caption = style.styled(f"  rows: {_short(grid.axes[0])}, columns: {_short(grid.axes[1])}; "
                           f"cells: hits (pass rate), '.' a hole", "grey50")
    return caption, table


_short = short_name


def axes_title(axes: tuple[str, ...]) -> str:
    """The corner of a grid: the parameter down the rows, then the one across the columns."""
    return f"{_short(axes[0])} ↓  {_short(axes[1])} →"


def _scatter(item: ItemResult, style: _Style) -> list[Text] | None:
    """A cross of two drawn ranges as a character map of its cells: '.' no run, 'o' runs that all passed,
    'x' a failing run among them (the HTML report draws each run as a point)."""
    grid = item.cross
    if not item.points or grid is None or len(grid.labels) != 2:
        return None
    rows, columns = grid.labels
    lines = [style.styled(f"  {len(item.points)} run(s); {axes_title(grid.axes)} {columns[0]} … {columns[-1]}; "
                          f"'o' runs passed, 'x' a run failed, '.' no run", "grey50")]
    for r, label in enumerate(rows):
        line = Text(f"  {label:>{max(len(x) for x in rows)}} ")
        for c in range(len(columns)):
            bucket = item.buckets[r * len(columns) + c]
            if bucket.runs == 0:
                line.append(".", style="" if style.plain else "grey37")
            elif bucket.failed or bucket.errored:
                line.append("x", style="" if style.plain else "bold red")
            else:
                line.append("o", style="" if style.plain else "green")
        lines.append(line)
    return lines


def _holes(item: ItemResult, style: _Style) -> Text | None:
    if not item.holes or not item.graded:
        return None
    text = Text()
    for title, found, colour in (("holes", item.plain_holes, "red"),
                                 ("not sampled, only failing runs were here", item.not_sampled, "yellow")):
        if found:
            labels = [item.buckets[i].label for i in found[:MAX_HOLES]]
            more = f" +{len(found) - MAX_HOLES} more" if len(found) > MAX_HOLES else ""
            text.append(("\n" if text else "") + f"  {title} ({len(found)}): " + ", ".join(labels) + more,
                        style="" if style.plain else colour)
    return text


def _records(report: CoverageReport, style: _Style) -> Table | None:
    records = report.items_of("record")
    if not records:
        return None
    names = report.runs.names
    table = Table(title="Record items", box=style.box, title_justify="left")
    for column, justify in _RECORD_COLUMNS:
        table.add_column(column, justify=justify)
    for item in records:
        rec = item.record
        assert rec is not None
        ext = rec.extremes
        if ext is None:
            top = ", ".join(f"{v} ({n})" for v, n in rec.top_values) or "no sample"
            table.add_row(item.name, item.unit or "", str(rec.count), top, "", "", "", "")
            continue
        table.add_row(item.name, item.unit or "", str(rec.count), f"{ext.minimum:g}", names[ext.min_run],
                      f"{ext.median:g}", f"{ext.maximum:g}", names[ext.max_run])
    return table


def _failing(report: CoverageReport, style: _Style) -> Table | None:
    runs = report.runs
    failing = runs.failing()
    if not failing:
        return None
    table = Table(title=f"Failing runs ({len(failing)})", box=style.box, title_justify="left")
    for column in ("run", "verdict", "values", "reason", "log"):
        table.add_column(column)
    for i in failing[:MAX_FAILING_RUNS]:
        reason = (runs.reasons[i] or "").splitlines()[0][:MAX_REASON_CHARS] if runs.reasons[i] else ""
        table.add_row(runs.names[i], style.styled(runs.verdicts[i], "red"), runs.values_text(i), reason,
                      runs.logs[i] or runs.folders[i] or "")
    if len(failing) > MAX_FAILING_RUNS:
        table.add_row(f"… {len(failing) - MAX_FAILING_RUNS} more", "", "", "", "")
    return table


def plain_width(report: CoverageReport) -> int:
    """Columns for plain output (a file, a CI log): wide enough that no item name or cell is cut or
    wrapped, as there is no terminal width to fit (at least 120)."""
    longest = max((len(printable(item.name)) for item in report.items), default=0)
    runs = report.runs
    failing = max((len(printable(runs.names[i])) + len(printable(runs.values_text(i))) + min(len((runs.reasons[i] or "").split("\n")[0]),
                   MAX_REASON_CHARS) + len(runs.logs[i] or runs.folders[i] or "") for i in runs.failing()[:MAX_FAILING_RUNS]),
                  default=0)
    return max(120, longest + 100, failing + 30)


def render_text(report: CoverageReport, console: Console, *, plain: bool) -> None:
    """Print ``report`` on ``console``; ``plain`` uses ASCII bars and boxes and no colour.

    Every name and value came from results a child wrote: each is shown :func:`printable` (no ESC, CSI
    or OSC sequence reaches the terminal or the file), and ``console`` must be made with
    ``markup=False`` so that ``[bold]`` in a name is text, not style.
    """
    report = escaped(report)
    style = _Style(plain)
    console.print(Group(*_summary(report, style)))
    console.print()
    if report.search is not None:           # right after the summary: what a search found comes first
        from coverage_engine.coverage.render_search import search_lines

        head, *rows = search_lines(report.search)
        console.print(style.styled(head, "bold"))
        for row in rows:
            console.print(Text(row))
        console.print()
    if any(i.graded for i in report.items):
        console.print(_overview(report, style))
        console.print()
    names = report.runs.names
    for item in report.items:
        if item.kind == "record":
            continue
        console.print(_title(item, style))
        for note in item.notes:
            console.print(style.styled(f"  note: {note}", "yellow"))
        scatter = _scatter(item, style)
        grid = _grid(item, style) if scatter is None else None
        if scatter is not None:
            for line in scatter:
                console.print(line)
        elif grid is not None:
            caption, cells = grid
            console.print(caption)
            console.print(cells)
        elif item.buckets:
            console.print(_bucket_table(item, names, style))
        if scatter is not None:
            holes = None        # a scatter's empty cells are no goal (weight 0 unless a plan names it)
        elif grid is None:
            holes = _holes(item, style)
        else:
            holes = style.styled(f"  holes: {len(item.holes)} of {len(item.buckets)} cells (the dots)",
                                 "red") if item.holes else None
        if holes is not None:
            console.print(holes)
        console.print()
    for section in (_records(report, style), _failing(report, style)):
        if section is not None:
            console.print(section)
            console.print()
    flaky = report.extra.get("flaky") or ()
    if flaky:                  # variants that passed and failed (their attempts, or the store's batches)
        console.print(style.styled(f"Flaky variants ({len(flaky)})", "yellow"))
        for name, what in flaky:
            console.print(Text(f"  {name} - {what}"))
        console.print()
