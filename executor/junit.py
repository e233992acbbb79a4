"""Write ``test.xml`` (JUnit, via junit-xml): one testcase per executed scenario.

A failed scenario carries its one-line reason as the failure message and the last tree snapshot as
the failure text; a scenario an abort kept from starting is a skipped testcase. A file that cannot be
parsed or resolved is reported as a single failing testcase (``parse_error_result``), so CI sees it
too. ``timestamp`` is the scenario's local start time in ISO 8601 (``2026-11-22T07:00:20``), the form
the JUnit schema asks for. The file is written to a temporary name and moved into place, so a reader
never sees half a report; :class:`ReportWriter` rewrites it after each scenario, so a ``kill -9``
loses only the scenario that was running.
"""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from executor.results import ScenarioResult

SUITE_NAME = "scenario_execution"
CLASSNAME = "tests.scenario"
RESULT_FILE = "test.xml"

# The process umask, read once (it can only be read by setting it), so reports get the usual mode.
_UMASK = os.umask(0o022)
os.umask(_UMASK)


def write_report(path: str | os.PathLike[str], xml_text: str) -> None:
    """Write the report atomically: the old file is replaced only once the new one is complete."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".test.xml.", dir=target.parent)
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(xml_text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def iso_timestamp(epoch: float) -> str:
    """``epoch`` (seconds) as local time in ISO 8601 without fraction or zone, as JUnit readers expect."""
    return time.strftime("%Y-%m-%dT%H:%M:%S", time.localtime(epoch))


def parse_error_result(scenario_file: str, message: str, output: str = "") -> ScenarioResult:
    """The failing result recorded when ``scenario_file`` could not be loaded."""
    return ScenarioResult(f"Parsing of {scenario_file}", False, message, output or message)


def write_results(directory: str | os.PathLike, results: Sequence[ScenarioResult]) -> Path:
    """Write ``<directory>/test.xml`` for ``results`` (directory created if needed); returns the path."""
    from junit_xml import TestCase, TestSuite, to_xml_report_string

    cases = []
    for result in results:
        case = TestCase(result.name, classname=CLASSNAME, elapsed_sec=round(result.duration, 6),
                        timestamp=iso_timestamp(result.start_time) if result.start_time else None)
        if result.skipped:
            case.add_skipped_info(message=result.message or "not run")
        elif not result.passed:
            case.add_failure_info(message=result.message or "failed", output=result.output or result.message)
        cases.append(case)
    suite = TestSuite(SUITE_NAME, cases)
    text = to_xml_report_string([suite], prettyprint=True, encoding="utf-8")
    target = Path(directory) / RESULT_FILE
    write_report(target, text)
    return target


def write_grouped(results: Sequence[ScenarioResult], root: str | None, per_scenario: bool) -> list[Path]:
    """Write the report(s): one combined file in ``root``, or one per scenario output directory."""
    if not per_scenario:
        return [write_results(root, results)] if root else []
    groups: dict[str, list[ScenarioResult]] = {}
    for result in results:
        directory = result.output_dir or root
        if directory:
            groups.setdefault(directory, []).append(result)
    return [write_results(directory, group) for directory, group in groups.items()]


class ReportWriter:
    """Keeps ``test.xml`` up to date while scenarios finish: each :meth:`update` rewrites the report(s)
    whose content changed (atomically), so a killed run leaves the results of every finished scenario.
    """

    def __init__(self, root: str | None, per_scenario: bool) -> None:
        self.root = root
        self.per_scenario = per_scenario
        self._written: dict[str | None, tuple] = {}

    def update(self, results: Sequence[ScenarioResult]) -> list[Path]:
        """Write the report(s) for ``results`` (all results so far); returns the paths written."""
        if not self.per_scenario:
            groups = {self.root: list(results)} if self.root else {}
        else:
            groups = {}
            for result in results:
                directory = result.output_dir or self.root
                if directory:
                    groups.setdefault(directory, []).append(result)
        written = []
        for directory, group in groups.items():
            key = tuple((id(r), r.passed, r.skipped, r.message) for r in group)
            if self._written.get(directory) == key:
                continue
            written.append(write_results(directory, group))
            self._written[directory] = key
        return written
