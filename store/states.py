"""The job state machine: the one place that names job states and the moves allowed between them.

Every status change in the queue is one guarded ``UPDATE … WHERE status IN (sources)`` built from
:data:`TRANSITIONS`, so a move this table does not allow can never reach the database.
"""

from __future__ import annotations

import enum


class JobState(str, enum.Enum):
    """Where a job is in its life: waiting, held by a worker, or ended with a verdict."""

    QUEUED = "queued"
    RUNNING = "running"
    PASSED = "passed"
    FAILED = "failed"
    ERROR = "error"
    TIMEOUT = "timeout"
    CANCELLED = "cancelled"

    def __str__(self) -> str:
        return self.value


#: States in which a job has a verdict that is never replaced.
FINAL = frozenset({JobState.PASSED, JobState.FAILED, JobState.ERROR, JobState.TIMEOUT})

#: States a batch still has work in (``cancelled`` jobs are run again by ``--resume``).
UNFINISHED = frozenset({JobState.QUEUED, JobState.RUNNING, JobState.CANCELLED})

#: The first claims of a job, within which losing it before its start costs it nothing: a holder lost
#: before the job's start was recorded (``QueueStore._reclaim``), a fork server that ended before it
#: forked the job (``job_run.goes_back_unstarted``); the job goes back to the queue. After them such a
#: loss is charged like any other, so a job whose every try ends its runner or server at once still ends,
#: after about a dozen tries.
UNCHARGED_CLAIMS = 10


class Transition(str, enum.Enum):
    """The named moves of the state machine; the store has one guarded UPDATE per name."""

    CLAIM = "claim"            # queued -> running: a worker takes the job and a lease on it
    FINISH = "finish"          # running -> a verdict: the attempt ended
    RETRY = "retry"            # running -> queued: an infrastructure error with retries left
    CANCEL = "cancel"          # running -> cancelled: Ctrl-C / SIGTERM stopped the attempt
    HALT = "halt"              # queued -> cancelled: --halt-on-failure stops jobs not started yet
    RECLAIM = "reclaim"        # running -> queued: the lease expired or the holder died
    ABANDON = "abandon"        # running -> error: the lease expired too often
    RESUME = "resume"          # cancelled -> queued: --resume runs stopped jobs again


#: For each transition: the states it may start from and the states it may end in.
TRANSITIONS: dict[Transition, tuple[frozenset[JobState], frozenset[JobState]]] = {
    Transition.CLAIM: (frozenset({JobState.QUEUED}), frozenset({JobState.RUNNING})),
    Transition.FINISH: (frozenset({JobState.RUNNING}), FINAL),
    Transition.RETRY: (frozenset({JobState.RUNNING}), frozenset({JobState.QUEUED})),
    Transition.CANCEL: (frozenset({JobState.RUNNING}), frozenset({JobState.CANCELLED})),
    Transition.HALT: (frozenset({JobState.QUEUED}), frozenset({JobState.CANCELLED})),
    Transition.RECLAIM: (frozenset({JobState.RUNNING}), frozenset({JobState.QUEUED})),
    Transition.ABANDON: (frozenset({JobState.RUNNING}), frozenset({JobState.ERROR})),
    Transition.RESUME: (frozenset({JobState.CANCELLED}), frozenset({JobState.QUEUED})),
}

#: The reason recorded on jobs a halt cancelled before they started (the merged report shows them as skipped).
HALT_REASON = "not started: --halt-on-failure after a failed job"

#: The reason recorded on the attempts ``--repeat until-fail`` kept from starting after their variant failed
#: (the merged report lists them as not run; ``--resume`` leaves them so).
UNTIL_FAIL_REASON = "not run: an earlier attempt of the variant failed (--repeat until-fail)"

#: The reason recorded on a claimed job whose command a cancel (Ctrl-C, SIGTERM) kept from starting.
NOT_STARTED_REASON = "cancelled before it started"

#: Verdicts worth another attempt when ``--retries`` allows: the scenario did not get to report a result.
RETRYABLE = frozenset({JobState.ERROR, JobState.TIMEOUT})


class TransitionError(Exception):
    """A state change the state machine does not allow was asked for."""


def sources(transition: Transition) -> frozenset[JobState]:
    """The states ``transition`` may start from (used in the WHERE clause of its UPDATE)."""
    return TRANSITIONS[transition][0]


def check(transition: Transition, target: JobState) -> JobState:
    """Return ``target`` if ``transition`` may end in it, else raise :class:`TransitionError`."""
    allowed = TRANSITIONS[transition][1]
    if target not in allowed:
        names = ", ".join(sorted(s.value for s in allowed))
        raise TransitionError(f"{transition.value} cannot end in {target.value} (allowed: {names})")
    return target


def allowed(source: JobState, target: JobState) -> bool:
    """Whether any transition moves a job from ``source`` to ``target``."""
    return any(source in src and target in dst for src, dst in TRANSITIONS.values())
