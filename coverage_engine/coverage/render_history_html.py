"""The HTML report's sections about failures and time: failures grouped by kind, the trend, the flaky list.

They read what the report model carries: the failing runs (:class:`RunTable`) for the triage, and
``report.extra`` for what comes from outside one batch: ``history`` (the batches as
:class:`~coverage_engine.coverage.trend.TrendPoint`), ``current`` (this batch's id) and ``flaky``
(``(variant, what it did)`` pairs). Every value is escaped.
"""

from __future__ import annotations

from html import escape

from coverage_engine.coverage.model import CoverageReport
from coverage_engine.coverage.trend import history_lines, trend_svg
from coverage_engine.coverage.triage import Failure, group_failures

#: Failure groups and their runs shown (the terminal and JSON have the same groups).
MAX_GROUPS, MAX_GROUP_RUNS = 12, 8


def triage_section(report: CoverageReport) -> str:
    """The failing runs grouped by kind, the largest group first, with the values each group shares."""
    runs = report.runs
    failing = runs.failing()
    if len(failing) < 2:
        return ""
    groups = group_failures(Failure(runs.names[i], runs.reasons[i] or runs.verdicts[i], runs.varied(i))
                            for i in failing)
    rows = []
    for group in groups[:MAX_GROUPS]:
        names = ", ".join(escape(n) for n in group.names[:MAX_GROUP_RUNS])
        if group.count > MAX_GROUP_RUNS:
            names += f" … {group.count - MAX_GROUP_RUNS} more"
        common = ", ".join(f"{escape(k.split('.', 1)[-1])}={escape(v)}" for k, v in group.common) or "—"
        rows.append(f'<tr><td class="num"><b>{group.count}</b></td><td class="mono">{escape(group.location or "—")}</td>'
                    f'<td class="reason" title="{escape(group.example)}">{escape(group.example)}</td>'
                    f'<td class="mono">{names}</td><td class="mono">{common}</td></tr>')
    more = f'<p class="muted">… {len(groups) - MAX_GROUPS} more kind(s)</p>' if len(groups) > MAX_GROUPS else ""
    return ('<section class="group" id="triage"><h2>Failures by kind '
            f'({len(failing)} in {len(groups)} group(s))</h2><p class="lead">Same location and same message with '
            'numbers and names masked; "shared values" are the varied values every run of the group has.</p>'
            '<table class="overview triage"><thead><tr><th class="num">runs</th><th>where</th><th>message (first)</th>'
            '<th>runs</th><th>shared values</th></tr></thead><tbody>' + "".join(rows) + f"</tbody></table>{more}</section>")


def trend_section(report: CoverageReport) -> str:
    """Pass rate, grade and runs per batch of the store as a chart, the current batch marked; the rows
    in a table below (what the chart's points say, for reading exact figures). One batch is no trend:
    the section needs two."""
    points = report.extra.get("history") or ()
    if len(points) < 2:
        return ""
    current = report.extra.get("current")
    table = escape("\n".join(history_lines(points[-30:], current)))
    return ('<section class="group" id="trend"><h2>Trend over batches</h2><p class="lead">Pass rate (green) and '
            'overall grade (blue) per batch, runs as grey bars; this batch outlined in red.</p>'
            f'{trend_svg(points, current)}<details class="more"><summary>the last {min(len(points), 30)} batch(es) '
            f'as a table</summary><pre class="mono">{table}</pre></details></section>')


def flaky_section(report: CoverageReport) -> str:
    """The flaky variants: passed and failed, in this batch's attempts or the store's earlier batches."""
    flaky = report.extra.get("flaky") or ()
    if not flaky:
        return ""
    rows = "".join(f'<tr><td class="mono">{escape(name)}</td><td>{escape(text)}</td></tr>' for name, text in flaky)
    return (f'<section class="group" id="flaky"><h2>Flaky variants ({len(flaky)})</h2><p class="lead">Each both '
            'passed and failed with the same scenario file: a pass or a failure of one run says little.</p>'
            '<table class="overview flaky"><thead><tr><th>variant</th><th>attempts</th></tr></thead><tbody>'
            + rows + "</tbody></table></section>")


def history_sections(report: CoverageReport) -> str:
    """The three sections in the order the page shows them: triage, trend, flaky."""
    return triage_section(report) + trend_section(report) + flaky_section(report)
