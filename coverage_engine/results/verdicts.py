"""Verdicts: the one word for how a run or a job ended, and how testcases fold into it.

A verdict is taken from the testcases, never from the totals attributes: any error makes ``error``,
else any failure ``failed``, else all skipped ``skipped``, else ``passed``; a report without a
testcase is an ``error``. A batch job's final state maps to a verdict by :data:`VERDICT_OF_STATE`
(a ``timeout`` is an ``error``; a job a cancel left is ``skipped``, one not finished ``pending``).
"""

from __future__ import annotations

import enum
import os
from collections.abc import Iterator
from dataclasses import dataclass, field

from coverage_engine.results.files import RESULT_FILE
from coverage_engine.results.read import JunitUnreadable, Suite, iter_suites

#: Largest single run's test.xml read; a merged report is streamed and may be larger.
MAX_RUN_XML_BYTES = 16 * 1024 * 1024


class Verdict(str, enum.Enum):
    """How a run ended, as reports count it."""

    PASSED = "passed"
    FAILED = "failed"
    ERROR = "error"
    SKIPPED = "skipped"
    #: Not finished yet (a batch job still queued or running); never the verdict of a report.
    PENDING = "pending"

    def __str__(self) -> str:
        return self.value


#: The verdicts that make a run count as failing (what ``--fail-under`` and failing-run lists look at).
FAILING = frozenset({Verdict.FAILED, Verdict.ERROR})

#: A batch job's state (as the store names it) as a verdict; the final states are the store's ``FINAL``.
VERDICT_OF_STATE: dict[str, Verdict] = {
    "passed": Verdict.PASSED, "failed": Verdict.FAILED, "error": Verdict.ERROR, "timeout": Verdict.ERROR,
    "cancelled": Verdict.SKIPPED, "queued": Verdict.PENDING, "running": Verdict.PENDING,
}

#: A testcase's outcome (the name of its JUnit result element) as a verdict.
_VERDICT_OF_OUTCOME = {"passed": Verdict.PASSED, "failure": Verdict.FAILED, "error": Verdict.ERROR,
                       "skipped": Verdict.SKIPPED}

#: Which verdict wins when testcases are folded into one.
_RANK = {Verdict.ERROR: 3, Verdict.FAILED: 2, Verdict.PASSED: 1, Verdict.SKIPPED: 0}


@dataclass
class SuiteVerdict:
    """One ``<testsuite>`` (a job of a merged report): name, properties, verdict and its reason."""

    name: str
    properties: dict[str, str] = field(default_factory=dict)
    verdict: Verdict = Verdict.ERROR
    reason: str | None = None
    cases: int = 0


def _fold(verdict: Verdict | None, outcome: Verdict) -> Verdict:
    if verdict is None:
        return outcome
    return outcome if _RANK[outcome] > _RANK[verdict] else verdict


def suite_verdict(suite: Suite) -> SuiteVerdict:
    """The verdict of one suite's testcases, with the first failure's (or skip's) message as its reason."""
    judged = SuiteVerdict(name=suite.name, properties=suite.properties, cases=len(suite.cases))
    verdict: Verdict | None = None
    for case in suite.cases:
        outcome = _VERDICT_OF_OUTCOME[case.outcome]
        message = None if outcome is Verdict.PASSED else case.message or case.type or outcome.value
        if outcome is not Verdict.SKIPPED:
            verdict = _fold(verdict, outcome)
        if message and judged.reason is None and outcome is not Verdict.PASSED:
            judged.reason = message
    if not suite.cases:
        judged.verdict, judged.reason = Verdict.ERROR, judged.reason or "no testcase in the report"
    elif verdict is None:
        judged.verdict = Verdict.SKIPPED
    else:
        judged.verdict = verdict
        if verdict is Verdict.PASSED:
            judged.reason = None
    return judged


def iter_suite_verdicts(path: str | os.PathLike[str]) -> Iterator[SuiteVerdict]:
    """The verdict of each ``<testsuite>`` of a report file, streamed (raises :class:`JunitUnreadable`)."""
    return (suite_verdict(suite) for suite in iter_suites(path))


def run_verdict(path: str | os.PathLike[str]) -> tuple[Verdict, str | None]:
    """The verdict and reason of one run's ``test.xml`` (all its suites and testcases together)."""
    try:
        if os.path.getsize(path) > MAX_RUN_XML_BYTES:
            return Verdict.ERROR, f"{RESULT_FILE} is larger than {MAX_RUN_XML_BYTES} bytes"
    except OSError as exc:
        return Verdict.ERROR, f"cannot read {RESULT_FILE}: {exc.strerror or exc}"
    verdict: Verdict | None = None
    reason = None
    cases = 0
    try:
        for suite in iter_suite_verdicts(path):
            cases += suite.cases
            if suite.cases and suite.verdict is not Verdict.SKIPPED:
                verdict = _fold(verdict, suite.verdict)
            if reason is None and suite.verdict in FAILING and suite.cases:
                reason = suite.reason
    except JunitUnreadable as exc:
        return Verdict.ERROR, f"{RESULT_FILE}: {exc}"
    if cases == 0:
        return Verdict.ERROR, f"{RESULT_FILE} has no testcase"
    if verdict is None:
        return Verdict.SKIPPED, None
    return verdict, reason if verdict in FAILING else None
