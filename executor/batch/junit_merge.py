"""The merged JUnit report of a batch: one testsuite per job, written with junit-xml.

Each suite is named after the job's file and holds the child's testcases. A child that reported one
testcase has it named after the job (so the variants of one scenario stay apart in CI), the original
name kept in the suite's ``testcase`` property; several testcases keep their names. A job without a
readable report becomes one testcase with an ``error`` carrying the exit code and the end of its log;
a timeout is an error of type ``timeout``. A job that ``--halt-on-failure`` kept from starting is one
skipped testcase, so CI's test count never shrinks. The report written when Ctrl-C (or SIGTERM) stopped
the batch also counts the jobs it stopped (an error of type ``cancelled``) and those it kept from
starting (skipped), so an interrupted batch never looks like a clean pass. Totals are computed by
junit-xml from the testcases.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from junit_xml import TestCase, TestSuite, to_xml_report_string

from executor.batch.junit_read import CaseRecord, JunitUnreadable, has_problem, read_cases
from store.jobs import Job
from store.states import FINAL, HALT_REASON, NOT_STARTED_REASON, JobState

#: Characters of a job's log repeated in the merged report (the store and log.txt keep more).
REPORT_LOG_CHARS = 16 * 1024

#: Above this many characters the report is written without indentation (pretty-printing costs memory).
_PRETTY_LIMIT = 8 * 1024 * 1024


def _case(record: CaseRecord, name: str | None = None) -> TestCase:
    case = TestCase(name or record.name, classname=record.classname, elapsed_sec=record.time,
                    stdout=record.stdout, stderr=record.stderr, timestamp=record.timestamp)
    # junit-xml counts a failure, error or skip only when it has a message or text, so a child's
    # bare <failure/> gets its kind as the message rather than turning into a pass.
    message = record.message or record.type or record.outcome
    if record.outcome == "failure":
        case.add_failure_info(message=message, output=record.text, failure_type=record.type)
    elif record.outcome == "error":
        case.add_error_info(message=message, output=record.text, error_type=record.type)
    elif record.outcome == "skipped":
        case.add_skipped_info(message=message, output=record.text)
    return case


#: The message of the skipped testcase of a job that a halt kept from running.
HALTED_MESSAGE = "not run: the batch halted after a failure"


def halted(job: Job) -> bool:
    """Whether ``--halt-on-failure`` cancelled the job before it started."""
    return job.status is JobState.CANCELLED and job.reason == HALT_REASON


#: The skipped message of a job an interruption kept from starting.
NOT_RUN_MESSAGE = "not run: the batch was interrupted; --resume runs it"

#: The error type of a job an interruption stopped while it ran.
CANCELLED_TYPE = "cancelled"


def interrupted_message(how: str) -> str:
    """The error message of a job stopped by an interruption (``how``: ``Ctrl-C``, ``SIGTERM``)."""
    return f"interrupted ({how}); run again with --resume"


def _not_started(job: Job) -> bool:
    """Whether an unfinished job never started its command (queued, or cancelled before it began)."""
    return job.status is JobState.QUEUED or (job.status is JobState.CANCELLED and job.reason == NOT_STARTED_REASON)


def _tail(text: str | None) -> str | None:
    if not text:
        return None
    return text[-REPORT_LOG_CHARS:]


def job_suite(job: Job, assignment: Mapping[str, object] | None = None,
              interrupted: str | None = None) -> TestSuite:
    """The testsuite of one job: a finished one, or (with ``interrupted``) one the interruption stopped."""
    cases: list[CaseRecord] = []
    if job.junit_xml:
        try:
            cases = read_cases(job.junit_xml)
        except JunitUnreadable:
            cases = []
    properties: dict[str, str] = {
        "scenario_file": job.scenario_path,
        "status": job.status.value,
        "attempts": str(job.attempts),
        "exit_code": "" if job.exit_code is None else str(job.exit_code),
    }
    if job.reason:
        properties["reason"] = job.reason
    if job.worker_host:
        properties["host"] = job.worker_host
    if job.output_dir:
        properties["output_dir"] = job.output_dir
    for key, value in sorted((assignment or {}).items()):
        properties[f"variation.{key}"] = str(value)

    exit_text = "no exit code" if job.exit_code is None else f"exit code {job.exit_code}"
    message = job.reason or job.status.value
    if "exit code" not in message and "killed by" not in message:
        message += f" ({exit_text})"
    kind = "timeout" if job.status is JobState.TIMEOUT else "error"
    test_cases: list[TestCase] = []
    if halted(job):
        case = TestCase(job.name, classname=job.name, elapsed_sec=None)
        case.add_skipped_info(message=HALTED_MESSAGE)
        test_cases.append(case)
    elif interrupted is not None and job.status not in FINAL:
        case = TestCase(job.name, classname=job.name, elapsed_sec=None)
        if _not_started(job):
            case.add_skipped_info(message=NOT_RUN_MESSAGE)
        else:
            case.elapsed_sec = job.duration
            case.add_error_info(message=interrupted_message(interrupted), output=_tail(job.log_tail),
                                error_type=CANCELLED_TYPE)
        test_cases.append(case)
    elif not cases:
        case = TestCase(job.name, classname=job.name, elapsed_sec=job.duration)
        if job.status is JobState.PASSED:
            pass
        elif job.status is JobState.FAILED:
            case.add_failure_info(message=message, output=_tail(job.log_tail), failure_type="failure")
        else:
            case.add_error_info(message=message, output=_tail(job.log_tail), error_type=kind)
        test_cases.append(case)
    else:
        if len(cases) == 1:
            properties["testcase"] = cases[0].name
            case = _case(cases[0], name=job.name)
            if case.elapsed_sec is None:
                case.elapsed_sec = job.duration        # the suite's time is the sum of its testcases
            test_cases.append(case)
        else:
            test_cases.extend(_case(c) for c in cases)
        if job.status in (JobState.ERROR, JobState.TIMEOUT):
            extra = TestCase(f"{job.name} [{job.status.value}]", classname=job.name, elapsed_sec=None)
            extra.add_error_info(message=message, output=_tail(job.log_tail), error_type=kind)
            test_cases.append(extra)
        elif job.status is JobState.FAILED and not has_problem(cases):
            extra = TestCase(f"{job.name} [exit code]", classname=job.name, elapsed_sec=None)
            extra.add_failure_info(message=message, output=_tail(job.log_tail), failure_type="exit-code")
            test_cases.append(extra)
    return TestSuite(job.name, test_cases, hostname=job.worker_host, properties=properties,
                     file=job.scenario_path)


def merged_report(jobs: Iterable[Job], assignments: Mapping[str, Mapping[str, object]] | None = None,
                  *, interrupted: str | None = None) -> str:
    """The merged JUnit XML of the jobs that have a verdict, and of those a halt kept from running (as skipped).

    Without ``interrupted`` queued, running and cancelled jobs are left out (a report of a batch still in
    progress). With it (``Ctrl-C``, ``SIGTERM``: the report written when that stopped the batch) every job
    is in: one stopped while it ran is an error of type ``cancelled``, one not started is skipped.
    """
    assignments = assignments or {}
    suites = []
    size = 0
    for job in jobs:
        if job.status not in FINAL and not halted(job) and interrupted is None:
            continue
        suites.append(job_suite(job, assignments.get(job.scenario_path), interrupted))
        size += len(job.junit_xml or "") + min(len(job.log_tail or ""), REPORT_LOG_CHARS)
    return to_xml_report_string(suites, prettyprint=size < _PRETTY_LIMIT)


