"""``--post-run CMD`` hooks of both commands: run ``CMD <folder>`` for each hook, in order.

``scenario_execution`` runs them once after all scenarios on the output folder (their output on the
terminal); ``scenario_batch_execution`` after each job on the job's folder (their output appended to
``post_run.log`` there). No shell is started: the text is split like a shell would. Each hook runs in
its own process group with a 10-minute limit, after which the whole group is ended. A hook that fails
to start, fails or hangs is reported and the next one still runs; a cancel ends the running hook's
group and skips the rest.
"""

from __future__ import annotations

import shlex
import signal
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

from executor.children.process import ChildProcess, ProcessOutcome, kill_group

HOOK_TIMEOUT = 600.0
HOOK_GRACE = 5.0


def split_hook(hook: str) -> list[str]:
    """The argv of a hook; raises ValueError for empty or unbalanced text."""
    argv = shlex.split(hook)
    if not argv:
        raise ValueError("empty --post-run command")
    return argv


def _announce(argv: Sequence[str], announce: Callable[[str], None] | None, log_path: Path | None) -> None:
    """Say a hook's command line before it starts: to ``announce``, and into the log it writes to."""
    if announce is not None:
        announce(shlex.join(argv))
    if log_path is not None:
        with open(log_path, "ab") as log:
            log.write(f"$ {shlex.join(argv)}\n".encode())


def run_post_hooks(hooks: Sequence[str], output_dir: str | Path, *, log_path: Path | None = None,
                   cwd: str | None = None, timeout: float = HOOK_TIMEOUT, grace: float = HOOK_GRACE,
                   cancelled: Callable[[], bool] | None = None,
                   track: Callable[[ChildProcess | None], None] | None = None,
                   announce: Callable[[str], None] | None = None,
                   report: Callable[[str], None] | None = None,
                   environment: Mapping[str, str] | None = None) -> list[str]:
    """Run every hook on ``output_dir``; returns one message per hook that failed (each also to ``report``).

    ``log_path``: append each hook's command line and output to this file (else they share the terminal).
    ``cancelled``: asked before each hook; once true, the remaining hooks are skipped.
    ``track``: called with each hook's process before it starts and with None after it ended, so another
    thread can :meth:`ChildProcess.cancel` it (a cancel before the start means it never starts).
    ``announce``: called with the command line before each hook starts.
    ``environment``: variables set for the hooks on top of this process's.
    """
    problems: list[str] = []

    def problem(text: str) -> None:
        problems.append(text)
        if report is not None:
            report(text)

    for hook in hooks:
        if cancelled is not None and cancelled():
            break
        try:
            argv = split_hook(hook) + [str(output_dir)]
        except ValueError as exc:
            problem(f"post-run '{hook}': {exc}")
            continue
        _announce(argv, announce, log_path)
        child = ChildProcess(argv, None if log_path is None else str(log_path), cwd=cwd, timeout=timeout,
                             grace=grace, append=True, environment=environment)
        if track is not None:
            track(child)
        try:
            try:
                pid = child.start()
            except OSError as exc:
                problem(f"post-run '{hook}' could not start: {exc.strerror or exc}")
                continue
            try:
                outcome = child.wait()
            except BaseException:               # Ctrl-C in the main thread: the hook's group is not ours to keep
                if pid is not None:
                    kill_group(pid, signal.SIGTERM)
                raise
        finally:
            if track is not None:
                track(None)
        failure = _failure(hook, outcome, started=pid is not None, timeout=timeout)
        if failure is not None:
            problem(failure)
        if outcome.cancelled:
            break
    return problems


def _failure(hook: str, outcome: ProcessOutcome, *, started: bool, timeout: float) -> str | None:
    """What went wrong with a hook that ran (or was cancelled before it started), else None."""
    if outcome.timed_out:
        return f"post-run '{hook}' timed out after {timeout:g} s"
    if outcome.cancelled:
        return f"post-run '{hook}' cancelled" if started else f"post-run '{hook}' not run: cancelled"
    if outcome.returncode != 0:
        return f"post-run '{hook}' failed with exit code {outcome.returncode}"
    return None
