"""Charts of the HTML report drawn as inline SVG (no script, no network): the scatter of runs over two
drawn ranges.

A cross of two sampled ranges has far more cells than runs (20 × 20 buckets, 60 runs), so a grid of
cells is mostly empty and says little; each run as a point, coloured by its verdict, shows where the
failures lie and where the design left space.
"""

from __future__ import annotations

from html import escape

from coverage_engine.coverage.input_domains import nice_width
from coverage_engine.coverage.model import ItemResult, short_name
from coverage_engine.coverage.search_rounds import SearchSection
from coverage_engine.search_record import assignment_text, axis_text

WIDTH, HEIGHT = 640, 380
LEFT, RIGHT, TOP, BOTTOM = 64, 16, 14, 46

#: Point colours by verdict.
VERDICT_COLOURS = {"passed": "#2e9d5b", "failed": "#d23f3f", "error": "#e08a1e", "pending": "#8a94a6"}


def _ticks(low: float, high: float) -> list[float]:
    width = nice_width(high - low, 5) if high > low else 1.0
    first = -(-low // width) * width
    ticks: list[float] = []
    value = first
    while value <= high + width * 1e-9 and len(ticks) < 12:
        ticks.append(round(value, 10))
        value += width
    return ticks


def _label(name: str, unit: str) -> str:
    short = short_name(name)
    return f"{short} ({unit})" if unit else short


class _Frame:
    """The plot area of a scatter over two ranges: the scales, the grid with its ticks, the axis names."""

    def __init__(self, x: tuple[float, float], y: tuple[float, float], x_name: str, y_name: str) -> None:
        self.x_low, x_high = x
        self.y_low, y_high = y
        self.plot_w, self.plot_h = WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM
        self.x_span, self.y_span = (x_high - self.x_low) or 1.0, (y_high - self.y_low) or 1.0
        parts = [f'<rect x="{LEFT}" y="{TOP}" width="{self.plot_w}" height="{self.plot_h}" fill="#f7f9fc" '
                 'stroke="#c5ccd8"/>']
        for tick in _ticks(self.x_low, x_high):
            at = self.sx(tick)
            parts.append(f'<line x1="{at:.1f}" y1="{TOP}" x2="{at:.1f}" y2="{TOP + self.plot_h}" stroke="#e3e7ee"/>'
                         f'<text x="{at:.1f}" y="{TOP + self.plot_h + 16}" text-anchor="middle">{tick:g}</text>')
        for tick in _ticks(self.y_low, y_high):
            at = self.sy(tick)
            parts.append(f'<line x1="{LEFT}" y1="{at:.1f}" x2="{LEFT + self.plot_w}" y2="{at:.1f}" stroke="#e3e7ee"/>'
                         f'<text x="{LEFT - 6}" y="{at + 4:.1f}" text-anchor="end">{tick:g}</text>')
        parts.append(f'<text x="{LEFT + self.plot_w / 2:.0f}" y="{HEIGHT - 8}" text-anchor="middle" '
                     f'class="axisname">{escape(x_name)} →</text>'
                     f'<text transform="translate(16 {TOP + self.plot_h / 2:.0f}) rotate(-90)" text-anchor="middle" '
                     f'class="axisname">{escape(y_name)} →</text>')
        self.parts = parts

    def inside(self, x: float, y: float) -> bool:
        """Whether the point ``(x, y)`` lies within the two ranges (a mark outside them is not drawn)."""
        return 0 <= (x - self.x_low) / self.x_span <= 1 and 0 <= (y - self.y_low) / self.y_span <= 1

    def sx(self, value: float) -> float:
        return LEFT + self.plot_w * (value - self.x_low) / self.x_span

    def sy(self, value: float) -> float:
        return TOP + self.plot_h * (1 - (value - self.y_low) / self.y_span)

    def svg(self, css: str, label: str) -> str:
        return (f'<svg class="{css}" viewBox="0 0 {WIDTH} {HEIGHT}" width="{WIDTH}" height="{HEIGHT}" role="img" '
                f'aria-label="{escape(label)}">{"".join(self.parts)}</svg>')


def scatter_svg(item: ItemResult) -> str | None:
    """Every run of a cross of two drawn ranges as a point (x: first parameter, y: second); None when the
    item is not such a cross."""
    if not item.points or item.cross is None or len(item.axis_ranges) != 2:
        return None
    (x_low, x_high, x_unit), (y_low, y_high, y_unit) = item.axis_ranges
    x_name, y_name = (_label(a, r[2]) for a, r in zip(item.cross.axes, item.axis_ranges, strict=True))
    frame = _Frame((x_low, x_high), (y_low, y_high), x_name, y_name)
    ordered = sorted(item.points, key=lambda p: p[2] != "passed")      # failures drawn on top
    for x, y, verdict, name in ordered:
        colour = VERDICT_COLOURS.get(verdict, VERDICT_COLOURS["pending"])
        tip = escape(f"{name + ': ' if name else ''}{_label(item.cross.axes[0], x_unit)} = {x:.4g}, "
                     f"{_label(item.cross.axes[1], y_unit)} = {y:.4g}, {verdict}")
        frame.parts.append(f'<circle cx="{frame.sx(x):.1f}" cy="{frame.sy(y):.1f}" r="4.5" fill="{colour}" '
                           f'fill-opacity="0.85" stroke="#fff" stroke-width="1" class="pt {escape(verdict)}">'
                           f'<title>{tip}</title></circle>')
    legend = "".join(f'<span class="dot" style="background:{VERDICT_COLOURS[v]}"></span><span>{v}</span>'
                     for v in ("passed", "failed", "error"))
    return (frame.svg("scatter", f"runs over {x_name} and {y_name}")
            + f'<div class="heatlegend"><span>{len(item.points)} run(s), one point each</span>{legend}</div>')


#: Point colours by round of a search (round 1 the first colour; past the last they repeat).
ROUND_COLOURS = ("#4e79a7", "#f28e2b", "#59a14f", "#b07aa1", "#76b7b2", "#edc948", "#9c755f", "#e15759")


def round_colour(number: int) -> str:
    """The colour of round ``number``'s runs."""
    return ROUND_COLOURS[(number - 1) % len(ROUND_COLOURS)]


def _search_marks(section: SearchSection, frame: _Frame, x_key: str, y_key: str) -> list[str]:
    """The estimate drawn over the runs: the boundary (a line per axis, its error as a band, or the
    boundary variants ringed) and the worst case (a ring with its name)."""
    marks = []
    boundary = section.estimate.boundary
    for key, axis in boundary.axes.items() if boundary is not None else ():
        error = axis.error or 0.0
        tip = escape(f"boundary: {axis_text(key, axis)}")
        if key == x_key:
            left, right = frame.sx(axis.value - error), frame.sx(axis.value + error)
            at = frame.sx(axis.value)
            marks.append(f'<g class="boundary"><title>{tip}</title><rect x="{left:.1f}" y="{TOP}" '
                         f'width="{max(right - left, 0):.1f}" height="{frame.plot_h}" fill="#1c2430" fill-opacity="0.08"/>'
                         f'<line x1="{at:.1f}" y1="{TOP}" x2="{at:.1f}" y2="{TOP + frame.plot_h}" stroke="#1c2430" '
                         'stroke-width="2" stroke-dasharray="6 4"/></g>')
        elif key == y_key:
            top, bottom = frame.sy(axis.value + error), frame.sy(axis.value - error)
            at = frame.sy(axis.value)
            marks.append(f'<g class="boundary"><title>{tip}</title><rect x="{LEFT}" y="{top:.1f}" '
                         f'width="{frame.plot_w}" height="{max(bottom - top, 0):.1f}" fill="#1c2430" fill-opacity="0.08"/>'
                         f'<line x1="{LEFT}" y1="{at:.1f}" x2="{LEFT + frame.plot_w}" y2="{at:.1f}" stroke="#1c2430" '
                         'stroke-width="2" stroke-dasharray="6 4"/></g>')
    if boundary is not None and not boundary.axes:
        on_it = []
        for variant in boundary.variants:
            values = dict(variant)
            x, y = values.get(x_key), values.get(y_key)
            if isinstance(x, (int, float)) and isinstance(y, (int, float)) and frame.inside(float(x), float(y)):
                on_it.append((float(x), float(y), variant))
        on_it.sort(key=lambda p: (p[0], p[1]))
        if len(on_it) > 1:          # the boundary as a line through its variants, left to right
            line = " ".join(f"{frame.sx(x):.1f},{frame.sy(y):.1f}" for x, y, _ in on_it)
            marks.append(f'<polyline points="{line}" fill="none" stroke="#1c2430" stroke-width="2" '
                         'stroke-dasharray="6 4" class="boundary"><title>the boundary located so far</title>'
                         '</polyline>')
        for x, y, variant in on_it:
            marks.append(f'<circle cx="{frame.sx(x):.1f}" cy="{frame.sy(y):.1f}" r="7" fill="none" '
                         f'stroke="#1c2430" stroke-width="1.5" stroke-dasharray="3 2" class="boundary">'
                         f'<title>{escape("on the boundary: " + assignment_text(variant))}</title></circle>')
    worst = section.estimate.worst
    if worst is not None:
        values = dict(worst.assignment)
        x, y = values.get(x_key), values.get(y_key)
        if isinstance(x, (int, float)) and isinstance(y, (int, float)) and frame.inside(float(x), float(y)):
            cx, cy = frame.sx(float(x)), frame.sy(float(y))
            tip = escape(f"worst case: {worst.objective} = {worst.value:.4g} at {assignment_text(worst.assignment)}")
            marks.append(f'<g class="worst"><title>{tip}</title><circle cx="{cx:.1f}" cy="{cy:.1f}" r="10" '
                         'fill="none" stroke="#111" stroke-width="2.5"/>'
                         f'<text x="{cx + 13:.1f}" y="{cy - 8:.1f}" class="axisname">worst</text></g>')
    return marks


def search_svg(section: SearchSection) -> str | None:
    """The runs of a search over two drawn ranges, coloured by round (squares: not passed), with the
    boundary drawn and the worst case marked; None when the search did not draw two ranges."""
    if len(section.axes) != 2 or not section.points:
        return None
    (x_key, x_low, x_high, x_unit), (y_key, y_low, y_high, y_unit) = section.axes
    x_name, y_name = _label(x_key, x_unit), _label(y_key, y_unit)
    frame = _Frame((x_low, x_high), (y_low, y_high), x_name, y_name)
    for point in sorted(section.points, key=lambda p: p.round):       # later rounds on top
        colour = round_colour(point.round)
        cx, cy = frame.sx(point.x), frame.sy(point.y)
        tip = escape(f"{point.name}: round {point.round}, {x_name} = {point.x:.4g}, {y_name} = {point.y:.4g}, "
                     f"{point.verdict}")
        css = f'run r{point.round} {escape(point.verdict)}'
        if point.verdict == "passed":
            frame.parts.append(f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="4.5" fill="{colour}" stroke="#fff" '
                               f'stroke-width="1" class="{css}" data-round="{point.round}"><title>{tip}</title></circle>')
        else:
            frame.parts.append(f'<rect x="{cx - 4.5:.1f}" y="{cy - 4.5:.1f}" width="9" height="9" fill="{colour}" '
                               f'stroke="#1c2430" stroke-width="1.2" class="{css}" data-round="{point.round}">'
                               f'<title>{tip}</title></rect>')
    frame.parts.extend(_search_marks(section, frame, x_key, y_key))
    rounds = sorted({p.round for p in section.points})
    legend = "".join(f'<span class="dot" style="background:{round_colour(n)}"></span><span>round {n}</span>'
                     for n in rounds)
    return (frame.svg("search", f"runs of the search over {x_name} and {y_name}, by round")
            + f'<div class="heatlegend">{legend}</div><p class="lead">{len(section.points)} run(s): circles passed, '
              'squares did not; dashed: the boundary (a dashed ring: a boundary variant); a solid ring: the '
              'worst case.</p>')
