"""Batches over time: runs, pass rate, overall grade and holes per batch, as rows, JSON and a chart.

The rows come from wherever the batches are kept (the store, or the ``history.json`` a batch leaves
in its results folder); this module only shapes and draws them. The chart is inline SVG (no script,
no network): pass rate and grade as two lines over the batches, the runs as grey bars, the current
batch marked.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from html import escape

from coverage_engine.limits import read_bounded

#: The file a batch leaves in its results folder with the store's recent batches (the trend of the folder).
HISTORY_FILE = "history.json"

#: Format name and version of that file and of ``scenario_coverage history --json``.
HISTORY_FORMAT, HISTORY_VERSION = "scenario-coverage/history", 1

#: Batches a results folder's history keeps (the newest).
KEPT_BATCHES = 200


@dataclass(frozen=True)
class TrendPoint:
    """One batch: when, how many runs (attempts) and variants, their pass rates, grade and holes."""

    batch: int
    created_at: float
    runs: int
    passed: int
    variants: int = 0
    variants_passed: int = 0
    flaky: int = 0
    grade: float | None = None
    holes: int | None = None
    output_dir: str = ""

    @property
    def pass_rate(self) -> float | None:
        """Passed runs over finished runs, in percent (None when none finished)."""
        return None if self.runs == 0 else 100.0 * self.passed / self.runs

    @classmethod
    def from_dict(cls, data: dict) -> TrendPoint:
        known = {k: data[k] for k in cls.__dataclass_fields__ if k in data}
        return cls(**known)


def history_document(points: Sequence[TrendPoint], current: int | None = None) -> dict:
    """The rows as the JSON document ``history --json`` prints and ``history.json`` holds."""
    rows = []
    for point in points:
        row = asdict(point)
        row["pass_rate"] = None if point.pass_rate is None else round(point.pass_rate, 2)
        row["grade"] = None if point.grade is None else round(point.grade, 2)
        rows.append(row)
    return {"format": HISTORY_FORMAT, "format_version": HISTORY_VERSION, "current": current, "batches": rows}


def read_history_document(text: str) -> tuple[list[TrendPoint], int | None]:
    """The rows and the current batch of a history document; ``ValueError`` when it is not one."""
    data = json.loads(text)
    if not isinstance(data, dict) or data.get("format") != HISTORY_FORMAT:
        raise ValueError(f"not a {HISTORY_FORMAT} document")
    rows = data.get("batches")
    if not isinstance(rows, list):
        raise ValueError("'batches' is not a list")
    current = data.get("current")
    return [TrendPoint.from_dict(row) for row in rows if isinstance(row, dict)], \
        current if isinstance(current, int) else None


#: Largest ``history.json`` read (200 batches take about 60 kB).
MAX_HISTORY_BYTES = 4 * 1024 * 1024


def read_history_file(folder: str) -> tuple[list[TrendPoint], int | None]:
    """The trend a batch left in its results folder (``history.json``); nothing when there is none, it is
    a link, larger than :data:`MAX_HISTORY_BYTES` or not a history document (the report goes on without)."""
    data = read_bounded(os.path.join(folder, HISTORY_FILE), MAX_HISTORY_BYTES)
    if data is None:
        return [], None
    try:
        return read_history_document(data.decode("utf-8"))
    except (ValueError, TypeError):
        return [], None


def _pct(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f} %"


def history_lines(points: Sequence[TrendPoint], current: int | None = None) -> list[str]:
    """A fixed-width table, one line per batch (oldest first), the current batch marked with ``*``."""
    header = f"{'batch':>7}  {'date':16}  {'runs':>7}  {'pass rate':>9}  {'variants':>8}  {'flaky':>5}  " \
             f"{'grade':>7}  {'holes':>5}"
    lines = [header]
    for p in points:
        mark = "*" if p.batch == current else " "
        when = time.strftime("%Y-%m-%d %H:%M", time.localtime(p.created_at))
        holes = "-" if p.holes is None else str(p.holes)
        lines.append(f"{mark}{p.batch:>6}  {when:16}  {p.runs:>7}  {_pct(p.pass_rate):>9}  {p.variants:>8}  "
                     f"{p.flaky:>5}  {_pct(p.grade):>7}  {holes:>5}")
    return lines


WIDTH, HEIGHT = 640, 240
LEFT, RIGHT, TOP, BOTTOM = 48, 48, 16, 40
PASS_COLOUR, GRADE_COLOUR, RUNS_COLOUR, CURRENT_COLOUR = "#2e9d5b", "#3b6fd4", "#d5d9e0", "#d23f3f"


def _polyline(values: Sequence[float | None], xs: Sequence[float], y_of: Callable[[float], float], colour: str,
              label: str) -> str:
    points = [f"{x:.1f},{y_of(v):.1f}" for x, v in zip(xs, values, strict=True) if v is not None]
    if not points:
        return ""
    dots = "".join(f'<circle cx="{p.split(",")[0]}" cy="{p.split(",")[1]}" r="2.5" fill="{colour}"/>'
                   for p in points)
    return (f'<polyline class="{label}" fill="none" stroke="{colour}" stroke-width="2" '
            f'points="{" ".join(points)}"/>{dots}')


def trend_svg(points: Sequence[TrendPoint], current: int | None = None) -> str:
    """Pass rate and grade (left axis, 0-100 %) and runs (grey bars, right axis) per batch; the current
    batch's column outlined in red. Empty for fewer than one point."""
    if not points:
        return ""
    plot_w, plot_h = WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM
    step = plot_w / len(points)
    xs = [LEFT + step * (i + 0.5) for i in range(len(points))]
    top_runs = max(p.runs for p in points) or 1

    def y_pct(value: float) -> float:
        return TOP + plot_h * (1 - value / 100.0)

    parts = [f'<svg class="trend" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {WIDTH} {HEIGHT}" '
             f'width="{WIDTH}" height="{HEIGHT}" role="img" aria-label="pass rate and grade per batch">']
    for tick in (0, 25, 50, 75, 100):
        y = y_pct(tick)
        parts.append(f'<line x1="{LEFT}" x2="{WIDTH - RIGHT}" y1="{y:.1f}" y2="{y:.1f}" stroke="#eceff3"/>'
                     f'<text x="{LEFT - 6}" y="{y + 4:.1f}" text-anchor="end" font-size="11">{tick} %</text>')
    bar = max(2.0, step * 0.6)
    for x, p in zip(xs, points, strict=True):
        height = plot_h * p.runs / top_runs
        title = escape(f"batch {p.batch}: {p.runs} run(s), pass rate {_pct(p.pass_rate)}, grade {_pct(p.grade)}, "
                       f"holes {'-' if p.holes is None else p.holes}")
        parts.append(f'<rect class="runs" x="{x - bar / 2:.1f}" y="{TOP + plot_h - height:.1f}" width="{bar:.1f}" '
                     f'height="{height:.1f}" fill="{RUNS_COLOUR}"><title>{title}</title></rect>')
        if p.batch == current:
            parts.append(f'<rect class="current" x="{x - step / 2:.1f}" y="{TOP}" width="{step:.1f}" '
                         f'height="{plot_h}" fill="none" stroke="{CURRENT_COLOUR}" stroke-width="2"/>')
    parts.append(_polyline([p.pass_rate for p in points], xs, y_pct, PASS_COLOUR, "pass-rate"))
    parts.append(_polyline([p.grade for p in points], xs, y_pct, GRADE_COLOUR, "grade"))
    every = max(1, len(points) // 10)
    for i, (x, p) in enumerate(zip(xs, points, strict=True)):
        if i % every == 0 or p.batch == current:
            parts.append(f'<text x="{x:.1f}" y="{HEIGHT - BOTTOM + 16}" text-anchor="middle" font-size="11">'
                         f'{p.batch}</text>')
    parts.append(f'<text x="{WIDTH - RIGHT + 6}" y="{TOP + 10}" font-size="11" fill="#6b7280">{top_runs} runs</text>'
                 f'<text x="{LEFT}" y="{HEIGHT - 6}" font-size="11" fill="{PASS_COLOUR}">● pass rate</text>'
                 f'<text x="{LEFT + 90}" y="{HEIGHT - 6}" font-size="11" fill="{GRADE_COLOUR}">● grade</text>'
                 f'<text x="{LEFT + 160}" y="{HEIGHT - 6}" font-size="11" fill="#8a94a6">▮ runs</text>'
                 f'<text x="{LEFT + 220}" y="{HEIGHT - 6}" font-size="11" fill="{CURRENT_COLOUR}">▭ this batch</text>'
                 f'<text x="{WIDTH - RIGHT}" y="{HEIGHT - 6}" font-size="11" text-anchor="end">batch</text></svg>')
    return "".join(parts)
