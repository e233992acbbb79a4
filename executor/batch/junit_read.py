"""Reading a child's JUnit XML safely (defusedxml) into plain testcase records.

Children are any program, so their XML is untrusted: entity tricks are refused, counts are taken from
the testcases themselves rather than from the (possibly wrong) totals attributes.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from defusedxml import ElementTree as SafeET
from defusedxml.common import DefusedXmlException

#: Characters XML 1.0 cannot carry (and PostgreSQL text cannot hold NUL); replaced before storing or writing.
_ILLEGAL_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


class JunitUnreadable(Exception):
    """The child's test.xml could not be read as JUnit XML."""


@dataclass(frozen=True)
class CaseRecord:
    """One testcase of a child's report: its names, time and, if it did not pass, what went wrong."""

    name: str
    classname: str | None = None
    time: float | None = None
    timestamp: str | None = None     # as the child wrote it (ISO 8601 from scenario_execution)
    outcome: str = "passed"          # passed | failure | error | skipped
    message: str | None = None
    type: str | None = None
    text: str | None = None
    stdout: str | None = None
    stderr: str | None = None


def clean_text(text: str) -> str:
    """``text`` without the characters XML 1.0 and PostgreSQL refuse."""
    return _ILLEGAL_XML.sub("\ufffd", text)


def _float(value: str | None) -> float | None:
    try:
        return float(value) if value not in (None, "") else None
    except ValueError:
        return None


def read_cases(xml_text: str) -> list[CaseRecord]:
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
                outcome = "failure" if tag == "failure" else tag
                message = found.get("message")
                kind = found.get("type")
                text = (found.text or "").strip() or None
                break
        out = case.find("system-out")
        err = case.find("system-err")
        cases.append(CaseRecord(
            name=case.get("name") or "unnamed", classname=case.get("classname"), time=_float(case.get("time")),
            timestamp=case.get("timestamp"), outcome=outcome, message=message, type=kind, text=text,
            stdout=None if out is None else out.text, stderr=None if err is None else err.text))
    return cases


def has_problem(cases: list[CaseRecord]) -> bool:
    """Whether any testcase failed or erred."""
    return any(c.outcome in ("failure", "error") for c in cases)
