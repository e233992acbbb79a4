"""``--repeat N`` and ``--repeat until-fail:N``: each variant run N times, judged by its pass rate.

Each attempt is a job of its own (its own folder ``<out>/<variant>@<k>``, its own store record and
coverage), so a crash or a timeout of one attempt is recorded like any job's. What the batch reports is
one verdict per *variant*: it passes when the share of its finished attempts that passed reaches
``--pass-rate`` (default 1.0: every attempt). The merged JUnit keeps one testcase per variant, the
attempts in its properties (``repeat.attempt.<k>``) and system-out, so CI counts one test per variant.

A variant whose attempts both passed and failed is *flaky* (:mod:`executor.batch.flaky` adds the
batches before this one). The attempt number reaches the job as ``$SCENARIO_ATTEMPT`` (1-based), so a
scenario may seed its random draws with it.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace

from executor.batch.junit_merge import child_cases
from store.jobs import Job, JobSpec
from store.states import FINAL, UNTIL_FAIL_REASON, JobState

#: Between a variant's name and its attempt number in a job's name (``cut4@3``).
ATTEMPT_MARK = "@"

#: The environment variable that tells a job which attempt it is (1-based); unset without ``--repeat``.
ATTEMPT_ENV = "SCENARIO_ATTEMPT"

#: How the report and the properties name an attempt that ``until-fail`` kept from starting.
NOT_RUN = "not run"


def attempt_name(variant: str, number: int) -> str:
    """The job name of attempt ``number`` (1-based) of ``variant``."""
    return f"{variant}{ATTEMPT_MARK}{number}"


def split_attempt(name: str) -> tuple[str, int | None]:
    """``('cut4', 3)`` for ``cut4@3``; ``(name, None)`` for a name that is not an attempt's."""
    variant, mark, number = name.rpartition(ATTEMPT_MARK)
    if mark and variant and number.isdigit():
        return variant, int(number)
    return name, None


def expand_specs(specs: Sequence[JobSpec], count: int) -> list[JobSpec]:
    """``count`` jobs per spec, a variant's attempts next to each other (so until-fail stops them in order)."""
    if count <= 1:
        return list(specs)
    return [replace(spec, name=attempt_name(spec.name, k)) for spec in specs for k in range(1, count + 1)]


def attempt_environment(job: Job, repeat: int) -> dict[str, str]:
    """``{SCENARIO_ATTEMPT: k}`` for an attempt of a repeated batch, else nothing."""
    if repeat <= 1:
        return {}
    number = split_attempt(job.name)[1]
    return {} if number is None else {ATTEMPT_ENV: str(number)}


def later_attempts(name: str, repeat: int) -> list[str]:
    """The job names of the attempts after ``name``'s, up to ``repeat`` (what until-fail stops)."""
    variant, number = split_attempt(name)
    return [] if number is None else [attempt_name(variant, k) for k in range(number + 1, repeat + 1)]


def attempt_reason(job: Job) -> str | None:
    """Why an attempt did not pass: its own report's first failure message, else the runner's reason."""
    if job.status is JobState.PASSED:
        return None
    problem = next((case for case in child_cases(job) if case.problem and case.message), None)
    text = problem.message if problem is not None and problem.message else job.reason or job.status.value
    return " ".join(text.split())


def attempt_outcome(job: Job) -> str:
    """An attempt as the report lists it: its verdict, or ``not run`` when it never ran to one."""
    return job.status.value if job.status in FINAL else NOT_RUN


@dataclass(frozen=True)
class VariantRepeats:
    """The attempts of one variant in a batch (in attempt order) and the pass rate they must reach."""

    variant: str
    attempts: tuple[Job, ...]
    required: float = 1.0
    #: Whether batches before this one ran the same variant (name and content) with the other outcome.
    flaky_before: bool = False

    @property
    def ran(self) -> tuple[Job, ...]:
        """The attempts that ended with a verdict."""
        return tuple(job for job in self.attempts if job.status in FINAL)

    @property
    def passed(self) -> int:
        return sum(1 for job in self.attempts if job.status is JobState.PASSED)

    @property
    def pass_rate(self) -> float | None:
        """Passed attempts over finished ones (None when none finished)."""
        ran = len(self.ran)
        return None if ran == 0 else self.passed / ran

    @property
    def flaky(self) -> bool:
        """Its attempts both passed and did not pass, here or (``flaky_before``) in earlier batches."""
        ran = len(self.ran)
        return (0 < self.passed < ran) or (ran > 0 and self.flaky_before)

    @property
    def status(self) -> JobState:
        """The variant's verdict: passed when the pass rate reaches ``required``, else the worst attempt's."""
        rate = self.pass_rate
        if rate is None:
            return self.attempts[0].status
        if rate >= self.required - 1e-9:
            return JobState.PASSED
        outcomes = {job.status for job in self.ran}
        return JobState.FAILED if JobState.FAILED in outcomes or JobState.PASSED in outcomes else \
            next(job.status for job in self.ran if job.status is not JobState.PASSED)

    def summary(self) -> str:
        """``passed 7 of 10 attempts (70 %, --pass-rate 100 %)``, the rate and the bar it is judged against."""
        rate = self.pass_rate
        shown = "-" if rate is None else f"{100 * rate:.0f} %"
        text = f"passed {self.passed} of {len(self.ran)} attempt(s) ({shown}, --pass-rate {100 * self.required:g} %)"
        skipped = len(self.attempts) - len(self.ran)
        return text + (f"; {skipped} not run" if skipped else "")

    def as_job(self) -> Job:
        """One job standing for the variant in the merged report: its first attempt that did not pass
        when the variant did not pass (its own report and log), else its last passing attempt, renamed
        to the variant and given the variant's verdict."""
        status = self.status
        if status is JobState.PASSED:
            chosen = [job for job in self.attempts if job.status is JobState.PASSED][-1]
        else:
            chosen = next((job for job in self.ran if job.status is not JobState.PASSED), self.attempts[0])
        reason = chosen.reason
        if status is not chosen.status or (status is JobState.FAILED and not reason):
            reason = self.summary()
        return replace(chosen, name=self.variant, status=status, reason=reason)

    def properties(self) -> dict[str, str]:
        """The JUnit properties of the variant's testcase: the rate, the bar, and each attempt."""
        rate = self.pass_rate
        out = {"repeat.count": str(len(self.attempts)), "repeat.passed": str(self.passed),
               "repeat.ran": str(len(self.ran)), "repeat.pass_rate": "" if rate is None else f"{rate:.4f}",
               "repeat.required": f"{self.required:g}", "flaky": "true" if self.flaky else "false"}
        for number, job in enumerate(self.attempts, 1):
            out[f"repeat.attempt.{number}"] = attempt_outcome(job)
            out[f"repeat.attempt.{number}.job"] = job.name
            reason = attempt_reason(job)
            if reason:
                out[f"repeat.attempt.{number}.reason"] = reason
        return out

    def attempts_text(self) -> str:
        """The attempts as lines for the testcase's system-out (one line each, then the rate)."""
        lines = [f"{self.variant}: {self.summary()}" + ("; flaky" if self.flaky else "")]
        for number, job in enumerate(self.attempts, 1):
            why = attempt_reason(job)
            reason = f" - {why}" if why else ""
            if job.reason == UNTIL_FAIL_REASON:
                reason = " - an earlier attempt failed (until-fail)"
            where = f" ({job.output_dir})" if job.output_dir else ""
            lines.append(f"  attempt {number}: {attempt_outcome(job)}{reason}{where}")
        return "\n".join(lines)


def group_attempts(jobs: Iterable[Job], required: float = 1.0,
                   flaky_before: frozenset[str] = frozenset()) -> list[VariantRepeats]:
    """The jobs of a repeated batch as variants, in the order of their first attempt; ``flaky_before``:
    the variants earlier batches saw both pass and fail."""
    found: dict[str, list[tuple[int, Job]]] = {}
    for job in jobs:
        variant, number = split_attempt(job.name)
        found.setdefault(variant, []).append((number or 0, job))
    return [VariantRepeats(variant, tuple(job for _, job in sorted(attempts, key=lambda a: a[0])), required,
                           variant in flaky_before)
            for variant, attempts in found.items()]


def variant_counts(groups: Iterable[VariantRepeats]) -> dict[JobState, int]:
    """How many variants ended in each state (every state present)."""
    counts = {state: 0 for state in JobState}
    for group in groups:
        counts[group.status] += 1
    return counts
