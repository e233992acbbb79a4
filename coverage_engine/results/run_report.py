"""Write ``test.xml`` for ``scenario_execution``: one testcase per executed scenario.

The document follows Jenkins' ``junit-10.xsd`` (built by :mod:`coverage_engine.results.document`) and names
its suite and testcases by the scheme of :mod:`coverage_engine.results.names`: the suite after the scenario
file, each testcase's classname after its source scenario and its name after the run (for a variant,
its file stem and varied values). A failed scenario carries its one-line reason as the failure
message and at the head of the failure text, followed by the last tree snapshot; a scenario an abort
kept from starting is a skipped testcase. A file that cannot be parsed or resolved is reported as a
single failing testcase (``parse_error_result``), so CI sees it too. The suite's ``timestamp`` is the
local start time of its first scenario in ISO 8601 (``2026-11-22T07:00:20``). The file is written to a
temporary name and moved into place, so a reader never sees half a report; :class:`ReportWriter`
rewrites it after each scenario, so a ``kill -9`` loses only the scenario that was running.
"""

from __future__ import annotations

import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from coverage_engine.results.atomic import write_text_atomically
from coverage_engine.results.document import Case, document, suite_element
from coverage_engine.results.files import RESULT_FILE
from coverage_engine.results.names import file_stem, scenario_classname, variant_name
from coverage_engine.results.scenario_result import ScenarioResult


def iso_timestamp(epoch: float) -> str:
    """``epoch`` (seconds) as local time in ISO 8601 without fraction or zone, as JUnit readers expect."""
    return time.strftime("%Y-%m-%dT%H:%M:%S", time.localtime(epoch))


@dataclass(frozen=True)
class ReportNames:
    """The names one scenario file's runs get in ``test.xml`` (see :mod:`coverage_engine.results.names`).

    ``cases`` maps a run name to its ``(classname, testcase name)``; a result without an entry (the
    file did not load) is named ``(classname, name)``.
    """

    suite: str
    classname: str
    name: str
    cases: Mapping[str, tuple[str, str]] = field(default_factory=dict)

    def of(self, run_name: str) -> tuple[str, str]:
        return self.cases.get(run_name, (self.classname, self.name if run_name.startswith(PARSING) else run_name))

    @classmethod
    def plain(cls, label: str = "scenario_execution") -> ReportNames:
        """Names for results that come from no particular file (tests, embedded use)."""
        return cls(suite=label, classname=label, name=label)


#: The start of the name of the result recorded for a file that could not be loaded.
PARSING = "Parsing of "


def report_names(scenario_file: str, runs: Sequence[tuple[str, str]] = (),
                 variant: tuple[str, str, Mapping[str, object], Mapping[str, str]] | None = None) -> ReportNames:
    """Names for the runs ``[(run name, scenario name)]`` of ``scenario_file``.

    ``variant`` is ``(source file, scenario, assignment, units of the drawn parameters)`` when the file is a
    variant (a ``.sce``).
    """
    stem = file_stem(scenario_file)
    if variant is None:
        cases = {run: (scenario_classname(stem, scenario), run) for run, scenario in runs}
        return ReportNames(suite=stem, classname=stem, name=stem, cases=cases)
    source, own, assignment, drawn = variant
    classname = scenario_classname(source, own)
    name = variant_name(stem, assignment, own, drawn)
    cases = {}
    for run, scenario in runs:
        if scenario == own:
            cases[run] = (classname, variant_name(stem + run[len(scenario):], assignment, own, drawn))
        else:
            cases[run] = (scenario_classname(source, scenario), f"{stem}:{run}")
    return ReportNames(suite=stem, classname=classname, name=name, cases=cases)


def parse_error_result(scenario_file: str, message: str, output: str = "") -> ScenarioResult:
    """The failing result recorded when ``scenario_file`` could not be loaded."""
    return ScenarioResult(f"{PARSING}{scenario_file}", False, message, output or message)


def failure_text(message: str, detail: str | None) -> str:
    """The text of a failure element: the reason first (GitLab shows only the text), then the detail."""
    detail = (detail or "").strip("\n")
    if not detail or detail == message:
        return message
    return f"{message}\n\n{detail}"


def _case(result: ScenarioResult, names: ReportNames) -> Case:
    classname, name = names.of(result.name)
    if result.skipped:
        return Case(name, classname, result.duration, "skipped", message=result.message or "not run")
    if not result.passed:
        message = result.message or "failed"
        return Case(name, classname, result.duration, "error" if result.error else "failure", message=message,
                    text=failure_text(message, result.output))
    return Case(name, classname, result.duration)


def results_xml(results: Sequence[ScenarioResult], names: ReportNames | None = None) -> str:
    """The ``test.xml`` text for ``results``."""
    names = names or ReportNames.plain()
    starts = [r.start_time for r in results if r.start_time]
    properties = {key: value for r in results for key, value in getattr(r, "properties", {}).items()}
    suite = suite_element(names.suite, [_case(r, names) for r in results],
                          timestamp=iso_timestamp(min(starts)) if starts else None, properties=properties or None)
    return document([suite])


def write_results(directory: str | os.PathLike, results: Sequence[ScenarioResult],
                  names: ReportNames | None = None) -> Path:
    """Write ``<directory>/test.xml`` for ``results`` (directory created if needed); returns the path."""
    target = Path(directory) / RESULT_FILE
    write_text_atomically(target, results_xml(results, names), durable=False)
    return target


def _groups(results: Sequence[ScenarioResult], root: str | None, per_scenario: bool) -> dict:
    if not per_scenario:
        return {root: list(results)} if root else {}
    groups: dict[str, list[ScenarioResult]] = {}
    for result in results:
        directory = result.output_dir or root
        if directory:
            groups.setdefault(directory, []).append(result)
    return groups


def write_grouped(results: Sequence[ScenarioResult], root: str | None, per_scenario: bool,
                  names: ReportNames | None = None) -> list[Path]:
    """Write the report(s): one combined file in ``root``, or one per scenario output directory."""
    return [write_results(directory, group, names)
            for directory, group in _groups(results, root, per_scenario).items()]


class ReportWriter:
    """Keeps ``test.xml`` up to date while scenarios finish: :meth:`update` rewrites the report(s) whose
    content changed (atomically), so a killed run leaves the results of the scenarios finished before
    the last write.

    Rewriting a report of k results costs k, so rewriting it after every one of n scenarios cost n²
    (a file of 2,500 short scenarios spent 114 of its 120 s there). A write therefore waits until the
    run has gone on for :data:`REWRITE_RATIO` times as long as the last write took: the reports cost
    at most a third of the run whatever its length, and while they are small (a millisecond) they are
    still rewritten after every scenario. ``final`` writes whatever changed.
    """

    #: How many times the last write's duration must pass before the next write.
    REWRITE_RATIO = 2.0

    def __init__(self, root: str | None, per_scenario: bool, names: ReportNames | None = None) -> None:
        self.root = root
        self.per_scenario = per_scenario
        self.names = names
        self._written: dict[str | None, tuple] = {}
        self._next_write = 0.0            # time.monotonic() before which no write is due

    def update(self, results: Sequence[ScenarioResult], *, final: bool = False) -> list[Path]:
        """Write the report(s) for ``results`` (all results so far) when a write is due (always when
        ``final``); returns the paths written."""
        started = time.monotonic()
        if not final and started < self._next_write:
            return []
        written = []
        for directory, group in _groups(results, self.root, self.per_scenario).items():
            key = tuple((id(r), r.passed, r.skipped, r.message) for r in group)
            if self._written.get(directory) == key:
                continue
            written.append(write_results(directory, group, self.names))
            self._written[directory] = key
        finished = time.monotonic()
        self._next_write = finished + self.REWRITE_RATIO * (finished - started)
        return written
