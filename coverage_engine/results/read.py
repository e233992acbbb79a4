"""The one reader of JUnit XML: a child's ``test.xml``, a run's own, or a batch's merged report.

Children are any program, so their XML is untrusted: it is read with defusedxml (entity tricks are
refused), counts are taken from the testcases themselves rather than from the (possibly wrong) totals
attributes, and a time that is not a number is taken as unknown. Every testcase becomes a
:class:`~coverage_engine.results.document.Case`. A whole document in memory (:func:`read_cases`, for
a job's report of bounded size) or streamed suite by suite (:func:`iter_suites`, so a merged report of
100,000 jobs never sits in memory whole).

Every entity trick (expansion bombs, external entities, a fetched DTD) needs a document type
declaration. A document held in memory without one is read by the standard library's C parser, which
then has nothing to expand or fetch; one with a declaration goes through defusedxml. The C parser reads
a child's small test.xml in half defusedxml's time, and a batch reads each one twice (to judge the job,
then to merge the report).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any
from xml.etree import ElementTree as StdET

from defusedxml import ElementTree as SafeET
from defusedxml.common import DefusedXmlException

from coverage_engine.results.document import Case, clean_text

__all__ = ["JunitUnreadable", "Suite", "clean_text", "has_problem", "iter_suites", "read_cases"]

#: The root elements a JUnit document may have.
_ROOTS = ("testsuites", "testsuite")

#: What opens a document type declaration, which every entity trick needs (XML spells it in capitals).
_DOCTYPE = "<!DOCTYPE"

#: The result elements of a testcase, in the order one is looked for (the first found wins).
_RESULT_TAGS = ("error", "failure", "skipped")


class JunitUnreadable(Exception):
    """A file or text is not JUnit XML we can read."""


@dataclass(frozen=True)
class Suite:
    """One ``<testsuite>`` read from a document: its name, properties and testcases."""

    name: str
    properties: dict[str, str]
    cases: tuple[Case, ...]


def _float(value: str | None) -> float | None:
    try:
        number = float(value) if value not in (None, "") else None
    except ValueError:
        return None
    return number if number is not None and number == number and number >= 0 else None


def _case(element: Any) -> Case:
    """The :class:`Case` of one ``<testcase>`` element."""
    outcome, message, kind, text = "passed", None, None, None
    for tag in _RESULT_TAGS:
        found = element.find(tag)
        if found is not None:
            outcome = tag
            message = found.get("message")
            kind = found.get("type")
            text = (found.text or "").strip() or None
            break
    out = element.find("system-out")
    err = element.find("system-err")
    return Case(name=element.get("name") or "unnamed", classname=element.get("classname") or "",
                time=_float(element.get("time")), outcome=outcome, message=message, type=kind, text=text,
                stdout=None if out is None else out.text, stderr=None if err is None else err.text)


class _Recent:
    """The testcases of the documents read lately, by their text: a batch reads each job's report twice (to
    judge the job, then to merge the report) and the second read is then a lookup. Bounded by the text
    held (:data:`RECENT_CHARS`: when full it starts again empty); :class:`Case` is immutable, so the
    cases are shared."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self._cases: dict[str, tuple[Case, ...]] = {}
        self._chars = 0
        self._lock = threading.Lock()

    def get(self, text: str) -> tuple[Case, ...] | None:
        return self._cases.get(text)

    def keep(self, text: str, cases: tuple[Case, ...]) -> None:
        if len(text) > self.limit:
            return
        with self._lock:
            if self._chars + len(text) > self.limit:
                self._cases.clear()
                self._chars = 0
            self._cases[text] = cases
            self._chars += len(text)


#: Most characters of report text :data:`_RECENT` holds: the memory it takes is about six times that with
#: the parsed cases (a 2,000-job batch's small reports fit many times over).
RECENT_CHARS = 2 * 1024 * 1024

_RECENT = _Recent(RECENT_CHARS)


def read_cases(xml_text: str) -> list[Case]:
    """The testcases of a JUnit document (``<testsuites>`` or a single ``<testsuite>``), in document order."""
    if not isinstance(xml_text, str):      # bytes could hide a declaration in another encoding from the check
        raise TypeError(f"read_cases reads text, not {type(xml_text).__name__}")
    known = _RECENT.get(xml_text)
    if known is not None:
        return list(known)
    cases = _parse_cases(xml_text)
    _RECENT.keep(xml_text, tuple(cases))
    return cases


def _parse_cases(xml_text: str) -> list[Case]:
    try:
        root = StdET.fromstring(xml_text) if _DOCTYPE not in xml_text else SafeET.fromstring(xml_text)
    except (SafeET.ParseError, DefusedXmlException, ValueError) as exc:
        raise JunitUnreadable(f"test.xml is not well-formed XML: {exc}") from None
    if root.tag not in _ROOTS:
        raise JunitUnreadable(f"test.xml has root <{root.tag}>, expected <testsuites> or <testsuite>")
    return [_case(case) for case in root.iter("testcase")]


def has_problem(cases: list[Case]) -> bool:
    """Whether any testcase failed or erred."""
    return any(case.problem for case in cases)


def _suite(element: Any) -> Suite:
    properties: dict[str, str] = {}
    holder = element.find("properties")
    if holder is not None:
        for prop in holder.iter("property"):
            name = prop.get("name")
            if name is not None:
                properties[name] = prop.get("value") or ""
    return Suite(name=element.get("name") or "", properties=properties,
                 cases=tuple(_case(case) for case in element.iter("testcase")))


def iter_suites(path: str | os.PathLike[str]) -> Iterator[Suite]:
    """Each ``<testsuite>`` of a report file, in document order (a bare ``<testsuite>`` root is one)."""
    try:
        root = None
        depth = 0
        for event, element in SafeET.iterparse(os.fspath(path), events=("start", "end")):
            if event == "start":
                if root is None:
                    root = element
                    if element.tag not in _ROOTS:
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
