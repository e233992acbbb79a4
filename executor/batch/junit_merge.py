"""The merged JUnit report of a batch: one testsuite per job, one testcase per scenario the job ran.

Each suite is named after the job's file and holds the child's testcases; the document follows
Jenkins' ``junit-10.xsd`` (:mod:`coverage_engine.results.document`). Names follow :mod:`coverage_engine.results.names`:
a child that reported one testcase has it named after the job (classname: the source scenario, name:
the variant with its varied values), whatever happened to the job; several testcases keep their names.

Whatever happens to a job, it keeps its testcases and adds none: a timeout, a crash, a non-zero exit
although test.xml passed, or a missing report becomes the result element of the job's testcase (the
one that was running or failed, else the last): an ``error`` whose ``type`` says which (``timeout``,
``error``, ``exit-code``, ``cancelled``), whose ``message`` is the reason (``timed out after 1.2 s``)
and whose text starts with that reason, followed by what the child reported. A job with no readable
report is one such testcase. A testcase of a job that did not pass carries the end of the job's
``log.txt`` in ``system-out``. A job that ``--halt-on-failure`` kept from starting is one skipped
testcase, so CI's test count never shrinks; the report written when Ctrl-C (or SIGTERM) stopped the
batch counts the jobs it stopped (error of type ``cancelled``) and those it kept from starting
(skipped). Totals are computed from the testcases.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from xml.etree import ElementTree as ET

from sqlalchemy import Engine

from coverage_engine.domains import HEADER_CHARS
from coverage_engine.results.document import Case, Totals, document, suite_element
from coverage_engine.results.names import declared_scenarios, drawn_units, scenario_classname, variant_name
from coverage_engine.results.read import JunitUnreadable, read_cases
from coverage_engine.results.run_report import failure_text, iso_timestamp
from coverage_engine.suffixes import OSC_SUFFIX, SCE_SUFFIX
from store.jobs import Job
from store.states import FINAL, HALT_REASON, NOT_STARTED_REASON, JobState
from store.variant_lookup import VariantInfo, variant_infos

#: Characters of a job's log repeated in the merged report (the store and log.txt keep more).
REPORT_LOG_CHARS = 16 * 1024

#: Above this many characters the report is written without indentation.
_PRETTY_LIMIT = 8 * 1024 * 1024

#: The message of the skipped testcase of a job that a halt kept from running.
HALTED_MESSAGE = "not run: the batch halted after a failure"

#: The skipped message of a job an interruption kept from starting.
NOT_RUN_MESSAGE = "not run: the batch was interrupted; --resume runs it"

#: The error type of a job an interruption stopped while it ran.
CANCELLED_TYPE = "cancelled"

#: Largest scenario file read to name a job that the store does not know as a variant.
_MAX_PEEK = 256 * 1024


def halted(job: Job) -> bool:
    """Whether ``--halt-on-failure`` cancelled the job before it started."""
    return job.status is JobState.CANCELLED and job.reason == HALT_REASON


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


@dataclass(frozen=True)
class JobNames:
    """The classname and name of a job's testcase (see :mod:`coverage_engine.results.names`)."""

    classname: str
    name: str


def _peek(path: str) -> str | None:
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            return handle.read(_MAX_PEEK)
    except OSError:
        return None


def _variant_from_file(path: str) -> VariantInfo | None:
    """A ``.sce`` that the store does not know: its own header says what it is."""
    from coverage_engine.errors import OscError
    from coverage_engine.files.sce import parse_sce

    text = _peek(path)
    if text is None:
        return None
    try:
        document = parse_sce(text, path)
    except OscError:
        return None
    return VariantInfo(document.assignment, document.scenario, document.source, text[:HEADER_CHARS])


def variants_of(engine: Engine, paths: Iterable[str]) -> dict[str, VariantInfo]:
    """What the store knows of the variants among ``paths``, with their variation's header (how drawn values
    are named)."""
    return variant_infos(engine, paths, HEADER_CHARS)


def job_names(job: Job, variant: VariantInfo | None = None) -> JobNames:
    """Names of the job's testcase: from the store's variant record, else the file itself, else its stem."""
    if variant is None and job.scenario_path.endswith(SCE_SUFFIX):
        variant = _variant_from_file(job.scenario_path)
    if variant is not None and variant.scenario:
        source = variant.source or job.name
        return JobNames(scenario_classname(source, variant.scenario),
                        variant_name(job.name, variant.assignment, variant.scenario, drawn_units(variant.header)))
    text = _peek(job.scenario_path) if job.scenario_path.endswith(OSC_SUFFIX) else None
    scenarios = declared_scenarios(text) if text else []
    stem = Path(job.scenario_path).stem or job.name
    return JobNames(scenario_classname(stem, scenarios[0] if len(scenarios) == 1 else None), job.name)


def _properties(job: Job, variant: VariantInfo | None, cases: list[Case]) -> dict[str, str]:
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
    for key, value in sorted((variant.assignment if variant else {}).items()):
        properties[f"variation.{key}"] = str(value)
    if len(cases) == 1:
        properties["testcase"] = cases[0].name
    return properties


#: The error type of each verdict that is not the scenario's own failure.
_ERROR_TYPES = {JobState.TIMEOUT: "timeout", JobState.ERROR: "error", JobState.CANCELLED: CANCELLED_TYPE}


def _job_problem(job: Job, cases: list[Case]) -> tuple[str, str, str] | None:
    """``(element, type, message)`` the job's own verdict puts on its testcase, or None when the child's cases say it all."""
    if job.status is JobState.PASSED:
        return None
    reason = job.reason or job.status.value
    if job.status is JobState.FAILED:
        if any(case.problem for case in cases):
            return None
        return "failure", "failure", reason
    kind = _ERROR_TYPES.get(job.status, "error")
    if job.status is JobState.ERROR and cases and "although its test.xml passed" in reason:
        kind = "exit-code"
    if job.status is JobState.ERROR and not cases and "exit code" not in reason and "killed by" not in reason:
        reason += " (no exit code)" if job.exit_code is None else f" (exit code {job.exit_code})"
    return "error", kind, reason


def _target(cases: list[Case]) -> int:
    """Which testcase a job-level problem belongs to: the first that failed or erred, else the last run."""
    for index, case in enumerate(cases):
        if case.problem:
            return index
    ran = [i for i, case in enumerate(cases) if case.outcome != "skipped"]
    return ran[-1] if ran else len(cases) - 1


def child_cases(job: Job) -> list[Case]:
    """The testcases of the job's own report (none when it has no readable one)."""
    if not job.junit_xml:
        return []
    try:
        return read_cases(job.junit_xml)
    except JunitUnreadable:
        return []


def job_cases(job: Job, names: JobNames, cases: list[Case], interrupted: str | None = None) -> list[Case]:
    """The testcases of one job, from the child's ``cases``: never none, never one more than the child reported."""
    cases = list(cases)
    if halted(job):
        return [Case(names.name, names.classname, None, "skipped", message=HALTED_MESSAGE)]
    if interrupted is not None and job.status not in FINAL:
        if _not_started(job):
            return [Case(names.name, names.classname, None, "skipped", message=NOT_RUN_MESSAGE)]
        message = interrupted_message(interrupted)
        return [Case(names.name, names.classname, job.duration, "error", message=message, type=CANCELLED_TYPE,
                     text=failure_text(message, None), stdout=_tail(job.log_tail))]
    if len(cases) == 1:
        time = cases[0].time if cases[0].time is not None else job.duration
        cases = [replace(cases[0], name=names.name, classname=names.classname, time=time)]
    elif not cases:
        cases = [Case(names.name, names.classname, job.duration)]
    problem = _job_problem(job, cases)
    if problem is not None:
        index = _target(cases)
        case = cases[index]
        element, kind, message = problem
        earlier = case.text or (case.message if case.outcome != "passed" else None)
        time = job.duration if job.duration is not None and job.status is JobState.TIMEOUT else case.time
        cases[index] = replace(case, outcome=element, type=kind, message=message,
                               text=failure_text(message, earlier), time=time)
    if job.status is not JobState.PASSED:
        log = _tail(job.log_tail)
        for index, case in enumerate(cases):
            if case.problem:
                if case.message and not (case.text or "").startswith(case.message):
                    case = replace(case, text=failure_text(case.message, case.text))
                cases[index] = case if case.stdout or not log else replace(case, stdout=log)
    return cases


@dataclass(frozen=True)
class JobNotes:
    """What a job's testsuite says beyond the job itself: more properties (a repeated variant's attempts,
    ``flaky``) and a text put first in each testcase's system-out."""

    properties: Mapping[str, str]
    stdout: str | None = None


def job_suite(job: Job, variant: VariantInfo | None = None, interrupted: str | None = None,
              notes: JobNotes | None = None) -> tuple[ET.Element, Totals]:
    """The testsuite of one job: a finished one, or (with ``interrupted``) one the interruption stopped.

    A variant the store does not know (recorded in another store, or copied from elsewhere) is named
    and given its ``variation.*`` properties from its own ``.sce`` header, so the values reach the report
    whatever store was used.
    """
    if variant is None and job.scenario_path.endswith(SCE_SUFFIX):
        variant = _variant_from_file(job.scenario_path)
    reported = child_cases(job)
    cases = job_cases(job, job_names(job, variant), reported, interrupted)
    properties = _properties(job, variant, reported)
    if notes is not None:
        properties.update(notes.properties)
        if notes.stdout:
            cases = [replace(case, stdout=notes.stdout + (f"\n\n{case.stdout}" if case.stdout else ""))
                     for case in cases]
    return suite_element(job.name, cases, timestamp=iso_timestamp(job.started_at) if job.started_at else None,
                         hostname=job.worker_host, file=job.scenario_path, properties=properties)


def merged_report(jobs: Iterable[Job], variants: Mapping[str, VariantInfo] | None = None,
                  *, interrupted: str | None = None, notes: Mapping[str, JobNotes] | None = None) -> str:
    """The merged JUnit XML of the jobs that have a verdict, and of those a halt kept from running (as skipped).

    Without ``interrupted`` queued, running and cancelled jobs are left out (a report of a batch still in
    progress). With it (``Ctrl-C``, ``SIGTERM``: the report written when that stopped the batch) every job
    is in: one stopped while it ran is an error of type ``cancelled``, one not started is skipped.
    ``notes``: by job name, what the job's suite says besides (:class:`JobNotes`).
    """
    variants = variants or {}
    notes = notes or {}
    suites = []
    size = 0
    for job in jobs:
        if job.status not in FINAL and not halted(job) and interrupted is None:
            continue
        suites.append(job_suite(job, variants.get(job.scenario_path), interrupted, notes.get(job.name)))
        size += len(job.junit_xml or "") + min(len(job.log_tail or ""), REPORT_LOG_CHARS)
    return document(suites, indent=size < _PRETTY_LIMIT)
