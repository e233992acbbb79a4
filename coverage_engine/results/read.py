"""Reading a child's JUnit XML safely (defusedxml) into :class:`~coverage_engine.results.document.Case` records.

Children are any program, so their XML is untrusted: entity tricks are refused, counts are taken from
the testcases themselves rather than from the (possibly wrong) totals attributes, and a time that is
not a number is taken as unknown.
"""

from __future__ import annotations

from defusedxml import ElementTree as SafeET
from defusedxml.common import DefusedXmlException

from coverage_engine.results.document import Case, clean_text

__all__ = ["JunitUnreadable", "clean_text", "has_problem", "read_cases"]


class JunitUnreadable(Exception):
    """The child's test.xml could not be read as JUnit XML."""


def _float(value: str | None) -> float | None:
    try:
        number = float(value) if value not in (None, "") else None
    except ValueError:
        return None
    return number if number is not None and number == number and number >= 0 else None


def read_cases(xml_text: str) -> list[Case]:
    """The testcases of a JUnit document (``<testsuites>`` or a single ``<testsuite>``), in document order."""
    try:
        root = SafeET.fromstring(xml_text)
    except (SafeET.ParseError, DefusedXmlException, ValueError) as exc:
        raise JunitUnreadable(f"test.xml is not well-formed XML: {exc}") from None
    if root.tag not in ("testsuites", "testsuite"):
        raise JunitUnreadable(f"test.xml has root <{root.tag}>, expected <testsuites> or <testsuite>")
    cases = []
    for case in root.iter("testcase"):
        outcome, message, kind, text = "passed", None, None, None
        for tag in ("error", "failure", "skipped"):
            found = case.find(tag)
            if found is not None:
                outcome = tag
                message = found.get("message")
                kind = found.get("type")
                text = (found.text or "").strip() or None
                break
        out = case.find("system-out")
        err = case.find("system-err")
        cases.append(Case(
            name=case.get("name") or "unnamed", classname=case.get("classname") or "",
            time=_float(case.get("time")), outcome=outcome, message=message, type=kind, text=text,
            stdout=None if out is None else out.text, stderr=None if err is None else err.text))
    return cases


def has_problem(cases: list[Case]) -> bool:
    """Whether any testcase failed or erred."""
    return any(case.problem for case in cases)
