"""The report as JSON (format ``scenario-coverage/report``, version 1; schema in ``docs/coverage.md``)."""

from __future__ import annotations

import json
from typing import Any

from coverage_engine.coverage.model import BucketResult, CoverageReport, ItemResult

FORMAT = "scenario-coverage/report"
FORMAT_VERSION = 1


def _percent(value: float | None) -> float | None:
    return None if value is None else round(value, 2)


def _bucket(bucket: BucketResult, names: tuple[str, ...]) -> dict[str, Any]:
    out: dict[str, Any] = {"label": bucket.label}
    if bucket.low is not None:
        out["low"], out["high"] = bucket.low, bucket.high
    out.update(hits=bucket.hits, passed=bucket.passed, failed=bucket.failed, errored=bucket.errored,
               pass_rate=_percent(bucket.pass_rate), covered=bucket.covered,
               failing_runs=[names[i] for i in bucket.failing_runs])
    if bucket.failed_here:
        out["failed_here"] = [names[i] for i in bucket.failed_here]
    return out


def _item(item: ItemResult, names: tuple[str, ...]) -> dict[str, Any]:
    out: dict[str, Any] = {
        "name": item.name, "kind": item.kind, "path": item.path, "type": item.type_text, "unit": item.unit,
        "text": item.text, "event": item.event, "ignore": item.ignore,
        "range": list(item.range) if item.range else None, "every": item.every,
        "weight": item.weight, "at_least": item.at_least, "grade": _percent(item.grade),
        "samples": item.samples, "runs_sampled": item.runs_sampled, "ignored": item.ignored,
        "notes": list(item.notes),
        "buckets": [_bucket(b, names) for b in item.buckets],
        "holes": [item.buckets[i].label for i in item.plain_holes],
        "not_sampled": [item.buckets[i].label for i in item.not_sampled],
    }
    if item.cross is not None:
        out["cross"] = {"axes": list(item.cross.axes), "labels": [list(axis) for axis in item.cross.labels]}
    if item.points:
        out["points"] = [{"x": x, "y": y, "verdict": verdict, "run": name or None} for x, y, verdict, name in item.points]
    if item.record is not None:
        rec, ext = item.record, item.record.extremes
        out["record"] = {
            "count": rec.count,
            "min": None if ext is None else {"value": ext.minimum, "run": names[ext.min_run]},
            "median": None if ext is None else ext.median,
            "max": None if ext is None else {"value": ext.maximum, "run": names[ext.max_run]},
            "top_values": [[value, count] for value, count in rec.top_values],
        }
    return out


def report_dict(report: CoverageReport) -> dict[str, Any]:
    """The JSON document of ``report``."""
    names = report.runs.names
    runs = report.runs
    return {
        "format": FORMAT, "format_version": FORMAT_VERSION,
        "source": report.source, "complete": report.complete, "plan": report.plan_file,
        "grade": _percent(report.grade),
        "runs": {"total": len(runs), **report.verdict_counts},
        "notes": list(report.notes), "warnings": list(report.warnings),
        "items": [_item(item, names) for item in report.items],
        "failing_runs": [{"name": names[i], "verdict": runs.verdicts[i], "values": runs.varied(i),
                          "reason": runs.reasons[i], "folder": runs.folders[i], "log": runs.logs[i]}
                         for i in runs.failing()],
    }


def render_json(report: CoverageReport) -> str:
    data = report_dict(report)
    flaky = report.extra.get("flaky") or ()
    if flaky:                  # only when there are: reports without flaky variants keep their form
        data["flaky"] = [{"name": name, "detail": what} for name, what in flaky]
    if report.search is not None:       # a search's runs only: other reports keep their form
        from coverage_engine.coverage.render_search import search_dict

        data["search"] = search_dict(report.search)
    return json.dumps(data, indent=1, ensure_ascii=False) + "\n"
