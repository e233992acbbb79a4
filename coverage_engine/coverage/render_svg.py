"""Charts of the HTML report drawn as inline SVG (no script, no network): the scatter of runs over two
drawn ranges.

A cross of two sampled ranges has far more cells than runs (20 × 20 buckets, 60 runs), so a grid of
cells is mostly empty and says little; each run as a point, coloured by its verdict, shows where the
failures lie and where the design left space.
"""

from __future__ import annotations

from html import escape

from coverage_engine.coverage.input_domains import nice_width
from coverage_engine.coverage.model import ItemResult

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
    short = name.removeprefix("input:").rsplit(".", 1)[-1]
    return f"{short} ({unit})" if unit else short


def scatter_svg(item: ItemResult) -> str | None:
    """Every run of a cross of two drawn ranges as a point (x: first parameter, y: second); None when the
    item is not such a cross."""
    if not item.points or item.cross is None or len(item.axis_ranges) != 2:
        return None
    (x_low, x_high, x_unit), (y_low, y_high, y_unit) = item.axis_ranges
    plot_w, plot_h = WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM
    x_span, y_span = (x_high - x_low) or 1.0, (y_high - y_low) or 1.0

    def sx(value: float) -> float:
        return LEFT + plot_w * (value - x_low) / x_span

    def sy(value: float) -> float:
        return TOP + plot_h * (1 - (value - y_low) / y_span)

    parts = [f'<rect x="{LEFT}" y="{TOP}" width="{plot_w}" height="{plot_h}" fill="#f7f9fc" stroke="#c5ccd8"/>']
    for tick in _ticks(x_low, x_high):
        x = sx(tick)
        parts.append(f'<line x1="{x:.1f}" y1="{TOP}" x2="{x:.1f}" y2="{TOP + plot_h}" stroke="#e3e7ee"/>'
                     f'<text x="{x:.1f}" y="{TOP + plot_h + 16}" text-anchor="middle">{tick:g}</text>')
    for tick in _ticks(y_low, y_high):
        y = sy(tick)
        parts.append(f'<line x1="{LEFT}" y1="{y:.1f}" x2="{LEFT + plot_w}" y2="{y:.1f}" stroke="#e3e7ee"/>'
                     f'<text x="{LEFT - 6}" y="{y + 4:.1f}" text-anchor="end">{tick:g}</text>')
    x_name, y_name = (escape(_label(a, r[2])) for a, r in zip(item.cross.axes, item.axis_ranges, strict=True))
    parts.append(f'<text x="{LEFT + plot_w / 2:.0f}" y="{HEIGHT - 8}" text-anchor="middle" class="axisname">'
                 f'{x_name} →</text>'
                 f'<text transform="translate(16 {TOP + plot_h / 2:.0f}) rotate(-90)" text-anchor="middle" '
                 f'class="axisname">{y_name} →</text>')
    ordered = sorted(item.points, key=lambda p: p[2] != "passed")      # failures drawn on top
    for x, y, verdict, name in ordered:
        colour = VERDICT_COLOURS.get(verdict, VERDICT_COLOURS["pending"])
        tip = escape(f"{name + ': ' if name else ''}{_label(item.cross.axes[0], x_unit)} = {x:.4g}, "
                     f"{_label(item.cross.axes[1], y_unit)} = {y:.4g}, {verdict}")
        parts.append(f'<circle cx="{sx(x):.1f}" cy="{sy(y):.1f}" r="4.5" fill="{colour}" fill-opacity="0.85" '
                     f'stroke="#fff" stroke-width="1" class="pt {escape(verdict)}"><title>{tip}</title></circle>')
    legend = "".join(f'<span class="dot" style="background:{VERDICT_COLOURS[v]}"></span><span>{v}</span>'
                     for v in ("passed", "failed", "error"))
    return (f'<svg class="scatter" viewBox="0 0 {WIDTH} {HEIGHT}" width="{WIDTH}" height="{HEIGHT}" role="img" '
            f'aria-label="runs over {x_name} and {y_name}">{"".join(parts)}</svg>'
            f'<div class="heatlegend"><span>{len(item.points)} run(s), one point each</span>{legend}</div>')
