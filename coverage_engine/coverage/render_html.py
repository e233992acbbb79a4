"""The report as one self-contained HTML page: inline CSS and SVG, no script, nothing fetched.

What a person looks at first: the overall grade (a ring), the runs by verdict (a stacked bar), then
every item with a bar per bucket (its length the hits, its colours the runs that passed, failed or
errored there), the holes hatched in red, a heat map per two-way cross (colour = pass rate, strength =
hits), the record items with min / median / max, and the failing runs with links to their folders and
logs (relative to the page, so the page and the results folder can move together).
"""

from __future__ import annotations

import math
import os
from html import escape
from importlib import resources
from urllib.parse import quote

from coverage_engine.coverage.model import KIND_TITLES, BucketResult, CoverageReport, ItemResult, short_name
from coverage_engine.coverage.render_history_html import history_sections
from coverage_engine.coverage.render_svg import scatter_svg

MAX_CHIPS = 6
MAX_NAMES_IN_DETAILS = 200
MAX_GRID_SIDE = 60
MAX_BUCKET_ROWS = 60          # more buckets are drawn as one histogram instead of a row each
MAX_FAILING_SHOWN = 50        # failing runs listed open; up to MAX_FAILING_ROWS more behind a click
MAX_FAILING_ROWS = 1000
MAX_HOLES = 200

_VERDICT_COLOURS = (("passed", "var(--pass)"), ("failed", "var(--fail)"), ("error", "var(--error)"),
                    ("skipped", "var(--skip)"), ("pending", "var(--pending)"))


def _css() -> str:
    return resources.files("coverage_engine.coverage").joinpath("report.css").read_text(encoding="utf-8")


def _pct(value: float | None, digits: int = 1) -> str:
    return "—" if value is None else f"{value:.{digits}f}%"


def _grade_colour(grade: float | None) -> str:
    if grade is None:
        return "var(--skip)"
    return "var(--good)" if grade >= 90 else "var(--fair)" if grade >= 60 else "var(--poor)"


def _rate_hue(rate: float) -> float:
    """Red (0 %) through orange and yellow to green (100 %); cubic, so that 85 % already looks amber-green
    rather than fine: failures are what a reader must notice."""
    return 125 * (min(max(rate, 0.0), 100.0) / 100) ** 3


_short = short_name       # the full name is above the map


class _Page:
    def __init__(self, report: CoverageReport, output_dir: str | None) -> None:
        self.report = report
        self.output_dir = output_dir
        self.names = report.runs.names

    # ------------------------------------------------------------------ helpers
    def href(self, path: str | None) -> str | None:
        if not path:
            return None
        if self.output_dir is not None:
            try:
                return quote(os.path.relpath(path, self.output_dir))
            except ValueError:
                pass
        return "file://" + quote(path)

    def run_link(self, run: int, css: str = "") -> str:
        runs = self.report.runs
        name = escape(self.names[run])
        target = self.href(runs.logs[run] or runs.folders[run])
        title = escape((runs.reasons[run] or runs.verdicts[run]).splitlines()[0][:200] if runs.reasons[run]
                       else runs.verdicts[run])
        if target is None:
            return f'<span class="chip" title="{title}">{name}</span>'
        return f'<a class="{css}" href="{target}" title="{title}">{name}</a>'

    @staticmethod
    def rate_pill(rate: float | None) -> str:
        if rate is None:
            return '<span class="rate muted">—</span>'
        hue = _rate_hue(rate)
        return (f'<span class="rate" style="background:hsl({hue:.0f},70%,92%);color:hsl({hue:.0f},65%,27%)">'
                f'{rate:.0f}%</span>')

    @staticmethod
    def grade_bar(grade: float | None) -> str:
        width = 0 if grade is None else max(grade, 1.5 if grade > 0 else 0)
        return (f'<span class="gradebar"><span style="width:{width:.1f}%;background:{_grade_colour(grade)}">'
                f'</span></span>')

    # ------------------------------------------------------------------ top of the page
    def donut(self) -> str:
        grade = self.report.grade
        radius, stroke = 44, 11
        circumference = 2 * math.pi * radius
        filled = circumference * (grade or 0) / 100
        label = "—" if grade is None else f"{grade:.0f}%"
        return (f'<svg class="donut" width="112" height="112" viewBox="0 0 112 112" role="img" '
                f'aria-label="overall grade {escape(label)}">'
                f'<circle cx="56" cy="56" r="{radius}" fill="none" stroke="#e3e7ee" stroke-width="{stroke}"/>'
                f'<circle cx="56" cy="56" r="{radius}" fill="none" stroke="{_grade_colour(grade)}" '
                f'stroke-width="{stroke}" stroke-linecap="round" stroke-dasharray="{filled:.2f} {circumference:.2f}" '
                f'transform="rotate(-90 56 56)"/>'
                f'</svg>')

    def cards(self) -> str:
        report = self.report
        counts = report.verdict_counts
        total = max(len(report.runs), 1)
        stack = "".join(f'<span style="width:{100 * counts.get(v, 0) / total:.3f}%;background:{c}" '
                        f'title="{counts.get(v, 0)} {v}"></span>' for v, c in _VERDICT_COLOURS if counts.get(v))
        legend = "".join(f'<span><i style="background:{c}"></i>{counts.get(v, 0)} {v}</span>'
                         for v, c in _VERDICT_COLOURS if counts.get(v))
        graded = [i for i in report.items if i.graded]
        holes = report.holes_count()
        with_holes = sum(1 for i in graded if i.holes)
        finished = counts.get("passed", 0) + counts.get("failed", 0) + counts.get("error", 0)
        rate = None if finished == 0 else 100 * counts.get("passed", 0) / finished
        plan = f'<div class="muted">plan: {escape(report.plan_file)}</div>' if report.plan_file else ""
        return (
            '<div class="cards">'
            f'<div class="card grade-card" id="overall">{self.donut()}<div><h3>Overall grade</h3>'
            f'<div class="big" style="color:{_grade_colour(report.grade)}">{_pct(report.grade)}</div>'
            f'<div class="muted">mean of {len(graded)} graded item(s)</div>{plan}</div></div>'
            f'<div class="card"><h3>Runs</h3><div class="big">{len(report.runs)}</div>'
            f'<div class="stack">{stack}</div><div class="legend">{legend}</div></div>'
            f'<div class="card"><h3>Holes</h3><div class="big" style="color:{"var(--poor)" if holes else "var(--good)"}">'
            f'{holes}</div><div class="muted">bucket(s) never reached, in {with_holes} of {len(graded)} item(s)</div></div>'
            f'<div class="card"><h3>Pass rate</h3><div class="big">{_pct(rate)}</div>'
            f'<div class="muted">of {finished} run(s) that finished</div></div>'
            '</div>')

    def callouts(self) -> str:
        out = []
        if not self.report.complete:
            out.append('<div class="callout"><b>Incomplete:</b> the batch is still running or was stopped; '
                       'this report covers the runs that have finished.</div>')
        out += [f'<div class="callout">{escape(n)}</div>' for n in self.report.notes]
        out += [f'<div class="callout warn">{escape(w)}</div>' for w in self.report.warnings]
        return "".join(out)

    def overview(self) -> str:
        rows = []
        for index, item in enumerate(self.report.items):
            if not item.graded:
                continue
            rows.append(
                f'<tr><td><a href="#item-{index}">{escape(item.name)}</a></td>'
                f'<td><span class="kind">{KIND_TITLES[item.kind]}</span></td>'
                f'<td>{self.grade_bar(item.grade)}<b style="color:{_grade_colour(item.grade)}">{_pct(item.grade)}</b></td>'
                f'<td class="num">{item.covered_count} / {len(item.buckets)}</td>'
                f'<td class="num">{len(item.holes)}</td><td class="num">{item.weight:g}</td></tr>')
        if not rows:
            return ""
        return ('<section class="group"><h2>Items at a glance</h2><table class="overview"><thead><tr>'
                '<th>item</th><th>kind</th><th>grade</th><th class="num">covered buckets</th>'
                '<th class="num">holes</th><th class="num">weight</th></tr></thead><tbody>'
                + "".join(rows) + "</tbody></table></section>")

    # ------------------------------------------------------------------ items
    def facts(self, item: ItemResult) -> str:
        facts = []
        if item.type_text:
            facts.append(escape(item.type_text))
        if item.unit:
            facts.append(f"unit {escape(item.unit)}")
        if item.range:
            every = f" every {item.every:g}" if item.every else ""
            facts.append(f"range [{item.range[0]:g}..{item.range[1]:g}]{every}")
        if item.event:
            facts.append(f"sampled at <code>{escape(item.event)}</code>")
        if item.ignore:
            facts.append(f"ignore: <code>{escape(item.ignore)}</code>")
        if item.at_least > 1:
            facts.append(f"at least {item.at_least} hits per bucket")
        if item.kind in ("input", "input_cross"):
            facts.append(f"{item.runs_sampled} run(s) reached a verdict with these values")
        else:
            facts.append(f"{item.samples} sample(s) from {item.runs_sampled} run(s)")
        if item.ignored:
            facts.append(f"{item.ignored} ignored")
        return " · ".join(facts)

    def chips(self, bucket: BucketResult) -> str:
        runs = bucket.rerun()
        if not runs:
            return ""
        shown = "".join(self.run_link(r) for r in runs[:MAX_CHIPS])
        if len(runs) > MAX_CHIPS:
            rest = runs[MAX_CHIPS:MAX_CHIPS + MAX_NAMES_IN_DETAILS]
            more = len(runs) - MAX_CHIPS - len(rest)
            tail = f' <span class="muted">… {more} more in the JSON report</span>' if more > 0 else ""
            shown += (f'<details><summary>+{len(runs) - MAX_CHIPS} more</summary>'
                      + "".join(self.run_link(r) for r in rest) + tail + "</details>")
        return f'<div class="chips">{shown}</div>'

    def bucket_rows(self, item: ItemResult) -> str:
        peak = max((b.hits for b in item.buckets), default=0) or 1
        rows = []
        for bucket in item.buckets[:MAX_BUCKET_ROWS]:
            if bucket.not_sampled:
                bar = (f'<div class="holebar notsampled">not sampled: {len(bucket.failed_here)} failed run(s) '
                       'were here</div>')
            elif bucket.hits == 0 or not bucket.covered:
                text = "hole" if bucket.hits == 0 else f"{bucket.hits} of {item.at_least} hits"
                bar = f'<div class="holebar">{text}</div>'
            else:
                width = 100 * bucket.hits / peak
                runs = bucket.runs
                parts = ((bucket.passed, "var(--pass)"), (bucket.failed, "var(--fail)"),
                         (bucket.errored, "var(--error)"))
                inner = ("".join(f'<span style="width:{100 * n / runs:.2f}%;background:{c}"></span>'
                                 for n, c in parts if n) if runs else
                         '<span style="width:100%;background:var(--pending)"></span>')
                bar = (f'<div class="hitbar" style="width:{width:.2f}%" title="{bucket.passed} passed, '
                       f'{bucket.failed} failed, {bucket.errored} error">{inner}</div>')
            rows.append(f'<tr><td class="label">{escape(bucket.label)}</td><td class="barcell">{bar}</td>'
                        f'<td class="num">{bucket.hits}</td><td class="num">{self.rate_pill(bucket.pass_rate)}</td>'
                        f'<td>{self.chips(bucket)}</td></tr>')
        more = len(item.buckets) - MAX_BUCKET_ROWS
        if more > 0:
            rows.append(f'<tr><td colspan="5" class="muted">… {more} more bucket(s) in the JSON report</td></tr>')
        return ('<table class="buckets"><thead><tr><th>bucket</th><th>hits (bar colours: runs passed / failed / '
                'error)</th><th class="num">hits</th><th class="num">pass rate</th><th>failing runs (rerun)</th>'
                '</tr></thead><tbody>' + "".join(rows) + "</tbody></table>")

    def histogram(self, item: ItemResult) -> str:
        """Many buckets: one bar each (height = hits, colour = pass rate), holes as red ticks on the axis."""
        width, height = 1000, 120
        count = len(item.buckets)
        step = width / count
        peak = max((b.hits for b in item.buckets), default=0) or 1
        bars = []
        for i, bucket in enumerate(item.buckets):
            x = i * step
            tip = escape(f"{bucket.label}: {bucket.hits} hit(s), pass rate {_pct(bucket.pass_rate, 0)}")
            if bucket.hits == 0 or not bucket.covered:
                bars.append(f'<rect x="{x:.2f}" y="{height - 4}" width="{max(step, 1):.2f}" height="4" '
                            f'fill="#d64545"><title>{tip}</title></rect>')
                continue
            bar = max(2.0, (height - 8) * bucket.hits / peak)
            rate = bucket.pass_rate
            colour = "#4a7fd4" if rate is None else f"hsl({_rate_hue(rate):.0f},62%,44%)"
            bars.append(f'<rect x="{x:.2f}" y="{height - 6 - bar:.2f}" width="{max(step - 0.3, 0.7):.2f}" '
                        f'height="{bar:.2f}" fill="{colour}"><title>{tip}</title></rect>')
        first, last = escape(item.buckets[0].label), escape(item.buckets[-1].label)
        return (f'<svg class="histogram" viewBox="0 0 {width} {height}" width="100%" height="{height}" '
                f'preserveAspectRatio="none" role="img" aria-label="hits per bucket">{"".join(bars)}</svg>'
                f'<div class="heatlegend"><span>{count} buckets, {first} … {last}; bar height: hits, colour: pass '
                'rate</span><span>0%</span><span class="scale"></span><span>100% pass</span>'
                '<span class="holekey"></span><span>hole (red tick)</span></div>')

    def heat_map(self, item: ItemResult) -> str | None:
        grid = item.cross
        if grid is None or len(grid.labels) != 2:
            return None
        rows, columns = grid.labels
        if len(rows) > MAX_GRID_SIDE or len(columns) > MAX_GRID_SIDE:
            return None
        peak = max((b.hits for b in item.buckets), default=0) or 1
        head = "".join(f'<th>{escape(c)}</th>' for c in columns)
        body = []
        for r, row_label in enumerate(rows):
            cells = []
            for c in range(len(columns)):
                bucket = item.buckets[r * len(columns) + c]
                tip = escape(f"{row_label} × {columns[c]}: {bucket.hits} hit(s), {bucket.passed} passed, "
                             f"{bucket.failed} failed, {bucket.errored} error")
                if bucket.not_sampled:
                    cells.append(f'<td class="hole notsampled" title="{tip}"><span>not sampled</span>'
                                 f'<span class="r">{len(bucket.failed_here)} failed</span></td>')
                    continue
                if bucket.hits == 0:
                    why = (f'<span class="r">{bucket.errored} error</span>' if bucket.errored else "")
                    cells.append(f'<td class="hole" title="{tip}"><span>hole</span>{why}</td>')
                    continue
                strength = 0.35 + 0.65 * math.sqrt(bucket.hits / peak)
                rate = bucket.pass_rate
                hue, sat = (215, 35) if rate is None else (_rate_hue(rate), 62)
                ink = "#fff" if strength > 0.6 else "#1c2430"
                style = f"background:hsla({hue:.0f},{sat}%,44%,{strength:.2f});color:{ink}"
                outline = "" if bucket.covered else ";outline:2px dashed var(--poor)"
                cells.append(f'<td style="{style}{outline}" title="{tip}"><span class="h">{bucket.hits}</span>'
                             f'<span class="r">{_pct(rate, 0)}</span></td>')
            body.append(f'<tr><th class="row">{escape(row_label)}</th>{"".join(cells)}</tr>')
        axis_rows, axis_columns = (escape(_short(a)) for a in grid.axes)
        full_rows, full_columns = (escape(a) for a in grid.axes)
        return (f'<div class="axes">rows: <b>{full_rows}</b> · columns: <b>{full_columns}</b></div>'
                f'<div class="heatwrap"><table class="heat"><thead><tr><th class="axis">{axis_rows} ↓ '
                f'{axis_columns} →</th>{head}</tr></thead><tbody>{"".join(body)}</tbody></table></div>'
                '<div class="heatlegend"><span>cell: hits, and pass rate of the runs there</span>'
                '<span>0%</span><span class="scale"></span><span>100% pass</span>'
                '<span>darker = more hits</span><span class="holekey"></span><span>hole</span></div>')

    def holes(self, item: ItemResult) -> str:
        if not item.holes:
            return '<div class="holes muted">No holes: every bucket reached its target.</div>'
        out = []
        for title, found, css in (("Holes", item.plain_holes, "hole"),
                                  ("Not sampled, only failing runs were here", item.not_sampled, "hole notsampled")):
            if not found:
                continue
            chips = "".join(f'<span class="{css}">{escape(item.buckets[i].label)}</span>' for i in found[:MAX_HOLES])
            more = f' <span class="muted">+{len(found) - MAX_HOLES} more</span>' if len(found) > MAX_HOLES else ""
            out.append(f'<div class="holes"><b>{title} ({len(found)}):</b> {chips}{more}</div>')
        return "".join(out)

    def item_card(self, index: int, item: ItemResult) -> str:
        grade = (f'<span class="grade" style="color:{_grade_colour(item.grade)}">{_pct(item.grade)}'
                 f'<span class="muted" style="font-weight:400;font-size:12px"> ({item.covered_count}/'
                 f'{len(item.buckets)})</span></span>' if item.graded and item.weight > 0 else
                 f'<span class="grade muted">{_pct(item.grade)} · weight 0</span>' if item.graded else
                 '<span class="grade muted">not graded</span>')
        text = f'<div class="text">{escape(item.text)}</div>' if item.text else ""
        notes = "".join(f'<div class="callout">{escape(n)}</div>' for n in item.notes)
        body = scatter_svg(item) or self.heat_map(item)
        if body is None and item.buckets:
            body = self.bucket_rows(item) if len(item.buckets) <= MAX_BUCKET_ROWS else self.histogram(item)
        return (f'<article class="item" id="item-{index}"><header><h3>{escape(item.name)}</h3>'
                f'<span class="kind">{KIND_TITLES[item.kind]}</span>{grade}</header>'
                f'<div class="facts">{self.facts(item)}</div>{text}{notes}{body or ""}'
                f'{self.holes(item) if item.graded and not item.points else ""}</article>')

    def item_groups(self) -> str:
        groups = (
            ("Varied parameters", "Input coverage for free: every parameter the variants varied, its values as "
                                  "buckets, and every pair of them crossed.", ("input", "input_cross")),
            ("Cover items", "Values measured by cover() items while the runs went.", ("cover", "cross")),
        )
        out = []
        indexed = list(enumerate(self.report.items))
        for title, lead, kinds in groups:
            cards = [self.item_card(i, item) for i, item in indexed if item.kind in kinds]
            if cards:
                out.append(f'<section class="group"><h2>{title}</h2><p class="lead">{lead}</p>{"".join(cards)}</section>')
        return "".join(out)

    # ------------------------------------------------------------------ records and failing runs
    @staticmethod
    def strip(low: float, median: float, high: float) -> str:
        span = (high - low) or 1.0
        m = 8 + 204 * (median - low) / span
        return ('<svg width="220" height="22" viewBox="0 0 220 22" role="img" aria-label="min, median, max">'
                '<line x1="8" y1="11" x2="212" y2="11" stroke="#c5ccd8" stroke-width="4" stroke-linecap="round"/>'
                '<circle cx="8" cy="11" r="5" fill="#3557c9"/><circle cx="212" cy="11" r="5" fill="#3557c9"/>'
                f'<rect x="{m - 2:.1f}" y="3" width="4" height="16" rx="1" fill="#1c2430"/></svg>')

    def records(self) -> str:
        rows = []
        for index, item in enumerate(self.report.items):
            if item.kind != "record" or item.record is None:
                continue
            rec = item.record
            unit = f" {escape(item.unit)}" if item.unit else ""
            name = f'<b id="item-{index}">{escape(item.name)}</b>' + (
                f'<div class="muted">{escape(item.text)}</div>' if item.text else "")
            ext = rec.extremes
            if ext is None:
                top = ", ".join(f"{escape(v)} ({n})" for v, n in rec.top_values) or "no sample"
                rows.append(f'<tr><td>{name}</td><td class="num">{rec.count}</td><td colspan="4">{top}</td></tr>')
                continue
            rows.append(
                f'<tr><td>{name}</td><td class="num">{rec.count}</td>'
                f'<td class="num">{ext.minimum:g}{unit}<div>{self.run_link(ext.min_run)}</div></td>'
                f'<td class="strip">{self.strip(ext.minimum, ext.median, ext.maximum)}</td>'
                f'<td class="num">{ext.median:g}{unit}</td>'
                f'<td class="num">{ext.maximum:g}{unit}<div>{self.run_link(ext.max_run)}</div></td></tr>')
        if not rows:
            return ""
        return ('<section class="group"><h2>Record items</h2><p class="lead">Raw values recorded by record() '
                'items (key performance indicators), with the run of each extreme.</p>'
                '<table class="overview records"><thead><tr><th>item</th><th class="num">samples</th>'
                '<th class="num">min (run)</th><th></th><th class="num">median</th><th class="num">max (run)</th>'
                '</tr></thead><tbody>' + "".join(rows) + "</tbody></table></section>")

    def failing_runs(self) -> str:
        runs = self.report.runs
        failing = runs.failing()
        if not failing:
            return ""

        def rows(ids: list[int]) -> str:
            out = []
            for i in ids:
                folder, log = self.href(runs.folders[i]), self.href(runs.logs[i])
                links = " · ".join(x for x in (f'<a href="{folder}">folder</a>' if folder else "",
                                               f'<a href="{log}">log</a>' if log else "") if x)
                reason = escape((runs.reasons[i] or "").strip().splitlines()[0] if runs.reasons[i] else "")
                out.append(f'<tr><td class="mono">{escape(runs.names[i])}</td>'
                           f'<td><span class="verdict {escape(runs.verdicts[i])}">{escape(runs.verdicts[i])}</span></td>'
                           f'<td class="mono">{escape(runs.values_text(i))}</td>'
                           f'<td class="reason" title="{reason}">{reason}</td><td>{links}</td></tr>')
            return "".join(out)

        head = ('<table class="overview runs"><thead><tr><th>run</th><th>verdict</th><th>values</th><th>reason</th>'
                '<th>files</th>'
                '</tr></thead><tbody>')
        shown, rest = failing[:MAX_FAILING_SHOWN], failing[MAX_FAILING_SHOWN:MAX_FAILING_ROWS]
        more = ""
        if rest:
            left = len(failing) - MAX_FAILING_SHOWN - len(rest)
            tail = f'<p class="muted">… {left} more in the JSON report</p>' if left > 0 else ""
            more = (f'<details class="more"><summary>{len(failing) - MAX_FAILING_SHOWN} more failing run(s)</summary>'
                    f'{head}{rows(rest)}</tbody></table>{tail}</details>')
        return (f'<section class="group" id="failing"><h2>Failing runs ({len(failing)})</h2><p class="lead">'
                'Each links to its folder and log; the variant name is what to rerun.</p>'
                f'{head}{rows(shown)}</tbody></table>{more}</section>')

    def search(self) -> str:
        """The rounds of a search and its estimate (nothing for the runs of any other batch)."""
        if self.report.search is None:
            return ""
        from coverage_engine.coverage.render_search import search_html

        return search_html(self.report.search)

    # ------------------------------------------------------------------ the page
    def page(self, generated: str) -> str:
        report = self.report
        state = ('<span class="pill complete">complete</span>' if report.complete else
                 '<span class="pill incomplete">in progress</span>')
        return (
            '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f'<title>Scenario coverage {_pct(report.grade)} — {escape(report.source)}</title>'
            f'<style>{_css()}</style></head><body>'
            f'<header class="top"><h1>Scenario coverage {state}</h1>'
            f'<div class="sub">{escape(report.source)} · {len(report.runs)} run(s) · generated {escape(generated)}'
            '</div></header><main>'
            + self.cards() + self.callouts() + self.search() + history_sections(report) + self.overview() + self.item_groups() + self.records()
            + self.failing_runs()
            + '<footer>scenario_coverage · one file, no network: share it as it is.</footer></main></body></html>\n')


def render_html(report: CoverageReport, *, output_dir: str | None = None, generated: str = "") -> str:
    """The page for ``report``; links to run folders are relative to ``output_dir`` (the page's folder)."""
    return _Page(report, output_dir).page(generated)
