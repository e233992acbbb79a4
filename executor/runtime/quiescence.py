"""When can ticking be skipped? The earliest scenario time at which a tick could change anything.

In step-based mode a tick in which every running leaf is only waiting for time (``wait elapsed``),
for an event not yet emitted, or for a condition over variables that is false now does nothing: no
action runs, so no variable or event changes, and the waits stay RUNNING until their deadline. The tick loop still calls
``simulation.step()`` once per ``dt`` but ticks the tree only from :func:`next_wake` on — the
scenario behaves exactly as if it were ticked every step, only faster.

Anything else running — an action (it may read the simulation), a decorator whose child has ended
and will be started again (``repeat``, ``retry``, ``success_is_running`` …), a composite we do not
know — means "tick at the next step" (:data:`NOW`).
"""

from __future__ import annotations

import math
from typing import cast

import py_trees
from py_trees.common import ParallelPolicy, Status

from executor.runtime import directives
from executor.runtime.modifiers import ClockTimeout

NOW = -math.inf
NEVER = math.inf

_PURE_DECORATORS = (py_trees.decorators.Inverter, py_trees.decorators.Repeat, py_trees.decorators.Retry,
                    py_trees.decorators.FailureIsRunning, py_trees.decorators.FailureIsSuccess,
                    py_trees.decorators.RunningIsFailure, py_trees.decorators.RunningIsSuccess,
                    py_trees.decorators.SuccessIsFailure, py_trees.decorators.SuccessIsRunning)


def next_wake(node: py_trees.behaviour.Behaviour) -> float:
    """Earliest clock time at which ticking ``node`` (RUNNING) could make a difference.

    The contract: for every clock time ``t < next_wake(root)`` a tick is a no-op.
    """
    kind = type(node)                  # exact types: a subclass may do more than wait
    if kind is directives.WaitElapsed:
        return cast(directives.WaitElapsed, node).finish
    if kind is directives.WaitEvent:
        # emitted later in the same tick (by a branch ticked after this one): seen next tick
        waiting = cast(directives.WaitEvent, node)
        return NOW if waiting.event in waiting.context.events else NEVER
    if kind is directives.WaitCondition:
        condition = cast(directives.WaitCondition, node)
        if not condition.pure:
            return NOW
        try:
            return NOW if condition.context.value(condition.condition) else NEVER
        except Exception:  # noqa: BLE001 - let the next tick report it
            return NOW
    if kind is py_trees.composites.Sequence:
        child = cast(py_trees.composites.Sequence, node).current_child
        return next_wake(child) if child is not None and child.status is Status.RUNNING else NOW
    if kind is py_trees.composites.Parallel:
        policy = cast(py_trees.composites.Parallel, node).policy
        synchronise = isinstance(policy, ParallelPolicy.SuccessOnAll) and policy.synchronise
        wake = NEVER
        for child in node.children:
            if child.status is Status.RUNNING:
                wake = min(wake, next_wake(child))
            elif not (synchronise and child.status is Status.SUCCESS):
                return NOW
            if wake == NOW:
                return NOW
        return wake
    if kind is ClockTimeout:
        timeout = cast(ClockTimeout, node)
        if timeout.decorated.status is not Status.RUNNING:
            return NOW
        # the timeout fires once the clock is strictly past its deadline
        return min(math.nextafter(timeout.finish, math.inf), next_wake(timeout.decorated))
    if kind in _PURE_DECORATORS:
        child = cast(py_trees.decorators.Decorator, node).decorated
        return next_wake(child) if child.status is Status.RUNNING else NOW
    return NOW
