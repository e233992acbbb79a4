"""Verdicts and properties from JUnit XML: a run's own ``test.xml`` or a batch's merged report.

Read with defusedxml (a child's XML is untrusted) and streamed suite by suite, so a merged report of
100,000 jobs never sits in memory whole. A verdict is taken from the testcases, never from the totals
attributes: any error makes ``error``, else any failure ``failed``, else all skipped ``skipped``, else
``passed``; a report without a testcase is an ``error``.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass, field

from defusedxml import ElementTree as SafeET
from defusedxml.common import DefusedXmlException

#: Largest single run's test.xml read; a merged report is streamed and may be larger.
MAX_RUN_XML_BYTES = 16 * 1024 * 1024


class JunitUnreadable(Exception):
    """The file is not JUnit XML we can read."""


@dataclass
class SuiteVerdict:
    """One ``<testsuite>`` (a job of a merged report): name, properties, verdict and its reason."""

    name: str
    properties: dict[str, str] = field(default_factory=dict)
    verdict: str = "error"
    reason: str | None = None
    cases: int = 0


def _fold(verdict: str | None, outcome: str) -> str:
    rank = {"error": 3, "failed": 2, "passed": 1, "skipped": 0}
    if verdict is None:
        return outcome
    return outcome if rank[outcome] > rank[verdict] else verdict


def _case_outcome(case) -> tuple[str, str | None]:
    for tag, outcome in (("error", "error"), ("failure", "failed"), ("skipped", "skipped")):
        found = case.find(tag)
        if found is not None:
            return outcome, found.get("message") or found.get("type") or outcome
    return "passed", None


def _suite(element) -> SuiteVerdict:
    suite = SuiteVerdict(name=element.get("name") or "")
    properties = element.find("properties")
    if properties is not None:
        for prop in properties.iter("property"):
            name = prop.get("name")
            if name is not None:
                suite.properties[name] = prop.get("value") or ""
    verdict: str | None = None
    all_skipped = True
    for case in element.iter("testcase"):
        suite.cases += 1
        outcome, message = _case_outcome(case)
        if outcome != "skipped":
            all_skipped = False
            verdict = _fold(verdict, outcome)
        if message and suite.reason is None and outcome in ("error", "failed"):
            suite.reason = message
        if outcome == "skipped" and suite.reason is None:
            suite.reason = message
    if suite.cases == 0:
        suite.verdict, suite.reason = "error", suite.reason or "no testcase in the report"
    elif all_skipped:
        suite.verdict = "skipped"
    else:
        suite.verdict = verdict or "passed"
        if suite.verdict == "passed":
            suite.reason = None
    return suite


def iter_suites(path: str | os.PathLike[str]) -> Iterator[SuiteVerdict]:
    """Each ``<testsuite>`` of a report, in document order (a bare ``<testsuite>`` root is one)."""
    try:
        context = SafeET.iterparse(os.fspath(path), events=("start", "end"))
        root = None
        depth = 0
        for event, element in context:
            if event == "start":
                if root is None:
                    root = element
                    if element.tag not in ("testsuites", "testsuite"):
                        raise JunitUnreadable(f"root element <{element.tag}>, expected <testsuites> or <testsuite>")
                if element.tag == "testsuite":
                    depth += 1
                continue
            if element.tag == "testsuite":
                depth -= 1
                if depth == 0:
                    yield _suite(element)
                    element.clear()
                    if root is not None and root is not element:
                        root.clear()
    except (SafeET.ParseError, DefusedXmlException, ValueError) as exc:
        raise JunitUnreadable(f"not well-formed XML: {exc}") from None
    except OSError as exc:
        raise JunitUnreadable(f"cannot read: {exc.strerror or exc}") from None


def run_verdict(path: str | os.PathLike[str]) -> tuple[str, str | None]:
    """The verdict and reason of one run's ``test.xml`` (all its suites and testcases together)."""
    try:
        if os.path.getsize(path) > MAX_RUN_XML_BYTES:
            return "error", f"test.xml is larger than {MAX_RUN_XML_BYTES} bytes"
    except OSError as exc:
        return "error", f"cannot read test.xml: {exc.strerror or exc}"
    verdict: str | None = None
    reason = None
    cases = 0
    all_skipped = True
    try:
        for suite in iter_suites(path):
            cases += suite.cases
            if suite.cases and suite.verdict != "skipped":
                all_skipped = False
                verdict = _fold(verdict, suite.verdict)
            if reason is None and suite.verdict in ("failed", "error") and suite.cases:
                reason = suite.reason
    except JunitUnreadable as exc:
        return "error", f"test.xml: {exc}"
    if cases == 0:
        return "error", "test.xml has no testcase"
    if all_skipped:
        return "skipped", None
    return verdict or "passed", reason if verdict in ("failed", "error") else None
