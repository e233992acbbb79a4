"""JUnit XML documents in the form CI tools validate: Jenkins' ``junit-10.xsd`` (Ant/Surefire form).

Both reports are built here: the ``test.xml`` of one ``scenario_execution`` run and the merged report
of a batch. Elements are made with :mod:`xml.etree.ElementTree`, so every attribute and text is
escaped by the library, and only what the schema allows is written:

* ``testsuites``: ``name``, ``tests``, ``failures``, ``errors``, ``time`` (no ``skipped``, no
  ``disabled``);
* ``testsuite``: the counts, ``time``, ``timestamp``, ``hostname``, ``file`` and ``properties``;
* ``testcase``: ``name``, ``classname``, ``time`` (no ``timestamp``: a case's start is its suite's),
  one ``failure``, ``error`` or ``skipped`` element, ``system-out`` and ``system-err``.

Totals are always computed from the testcases, never copied. Times are written as plain decimals
(``0.250000``): the schema's time pattern refuses exponents and signs.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from coverage_engine.printable import clean_text as clean_text  # (where the JUnit writers look for it)

#: The outcomes a testcase can have; all but ``passed`` are written as an element of that name.
OUTCOMES = ("passed", "failure", "error", "skipped")


def junit_time(seconds: float | None) -> str:
    """A duration as the schema's time pattern wants it: a non-negative plain decimal."""
    if seconds is None or seconds != seconds or seconds < 0:     # None, nan, negative
        seconds = 0.0
    return f"{min(seconds, 1e12):.6f}"


@dataclass(frozen=True)
class Case:
    """One testcase: names, time, and (unless it passed) its outcome with message, type and text."""

    name: str
    classname: str
    time: float | None = None
    outcome: str = "passed"          # one of OUTCOMES
    message: str | None = None
    type: str | None = None
    text: str | None = None
    stdout: str | None = None
    stderr: str | None = None

    @property
    def problem(self) -> bool:
        """Whether the case failed or erred (what makes a job or a run not pass)."""
        return self.outcome in ("failure", "error")


def case_element(case: Case) -> ET.Element:
    """The ``<testcase>`` element of ``case``."""
    element = ET.Element("testcase", {"name": clean_text(case.name), "classname": clean_text(case.classname),
                                      "time": junit_time(case.time)})
    if case.outcome != "passed":
        result = ET.SubElement(element, case.outcome)
        if case.type:
            result.set("type", clean_text(case.type))
        result.set("message", clean_text(case.message or case.outcome))
        if case.text:
            result.text = clean_text(case.text)
    if case.stdout:
        ET.SubElement(element, "system-out").text = clean_text(case.stdout)
    if case.stderr:
        ET.SubElement(element, "system-err").text = clean_text(case.stderr)
    return element


@dataclass
class Totals:
    """Counts and time of a set of testcases (a suite's, or the whole document's)."""

    tests: int = 0
    failures: int = 0
    errors: int = 0
    skipped: int = 0
    time: float = 0.0

    def add_case(self, case: Case) -> None:
        self.tests += 1
        self.failures += case.outcome == "failure"
        self.errors += case.outcome == "error"
        self.skipped += case.outcome == "skipped"
        self.time += case.time or 0.0

    def add(self, other: Totals) -> None:
        self.tests += other.tests
        self.failures += other.failures
        self.errors += other.errors
        self.skipped += other.skipped
        self.time += other.time


def suite_element(name: str, cases: Sequence[Case], *, timestamp: str | None = None,
                  hostname: str | None = None, file: str | None = None,
                  properties: Mapping[str, str] | None = None) -> tuple[ET.Element, Totals]:
    """A ``<testsuite>`` holding ``cases`` (counts computed from them) and its totals."""
    totals = Totals()
    for case in cases:
        totals.add_case(case)
    attributes = {"name": clean_text(name), "tests": str(totals.tests), "failures": str(totals.failures),
                  "errors": str(totals.errors), "skipped": str(totals.skipped), "time": junit_time(totals.time)}
    if timestamp:
        attributes["timestamp"] = timestamp
    if hostname:
        attributes["hostname"] = clean_text(hostname)
    if file:
        attributes["file"] = clean_text(file)
    suite = ET.Element("testsuite", attributes)
    if properties:
        holder = ET.SubElement(suite, "properties")
        for key, value in properties.items():
            ET.SubElement(holder, "property", {"name": clean_text(key), "value": clean_text(value)})
    suite.extend(case_element(case) for case in cases)
    return suite, totals


def document(suites: Iterable[tuple[ET.Element, Totals]], *, name: str | None = None,
             indent: bool = True) -> str:
    """The whole report: ``<testsuites>`` with totals over ``suites``, as text with an XML declaration."""
    root = ET.Element("testsuites")
    if name:
        root.set("name", clean_text(name))
    totals = Totals()
    for suite, suite_totals in suites:
        root.append(suite)
        totals.add(suite_totals)
    for key, value in (("tests", totals.tests), ("failures", totals.failures), ("errors", totals.errors)):
        root.set(key, str(value))
    root.set("time", junit_time(totals.time))
    if indent:
        ET.indent(root, space="  ")
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
