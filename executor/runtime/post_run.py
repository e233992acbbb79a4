"""``--post-run CMD``: after all scenarios, run ``CMD <output dir>`` for each hook, in order.

No shell is started (the text is split like a shell would). Each hook runs in its own process group
with a 10-minute limit; on timeout the whole group is ended. A failing or hanging hook is logged and
the next one still runs.
"""

from __future__ import annotations

import os
import shlex
import signal
import subprocess
import sys
from collections.abc import Sequence

from executor.runtime.logger import Logger

HOOK_TIMEOUT = 600.0


def split_hook(hook: str) -> list[str]:
    """The argv of a hook; raises ValueError for empty or unbalanced text."""
    argv = shlex.split(hook)
    if not argv:
        raise ValueError("empty --post-run command")
    return argv


def _kill_group(process: subprocess.Popen, signum: int) -> None:
    try:
        os.killpg(process.pid, signum)
    except (ProcessLookupError, PermissionError):
        pass


def run_post_hooks(hooks: Sequence[str], output_dir: str, logger: Logger,
                   timeout: float = HOOK_TIMEOUT) -> list[str]:
    """Run every hook on ``output_dir``; returns one message per hook that failed."""
    problems = []
    for hook in hooks:
        try:
            argv = split_hook(hook) + [output_dir]
        except ValueError as exc:
            problems.append(f"post-run '{hook}': {exc}")
            logger.error(problems[-1])
            continue
        logger.info(f"Running post-run: {shlex.join(argv)}")
        sys.stdout.flush()
        try:
            process = subprocess.Popen(argv, start_new_session=True)
        except OSError as exc:
            problems.append(f"post-run '{hook}' could not start: {exc.strerror or exc}")
            logger.error(problems[-1])
            continue
        try:
            code = process.wait(timeout)
        except subprocess.TimeoutExpired:
            _kill_group(process, signal.SIGTERM)
            try:
                process.wait(5)
            except subprocess.TimeoutExpired:
                _kill_group(process, signal.SIGKILL)
                process.wait()
            problems.append(f"post-run '{hook}' timed out after {timeout:g} s")
            logger.error(problems[-1])
            continue
        except BaseException:
            _kill_group(process, signal.SIGTERM)
            raise
        if code != 0:
            problems.append(f"post-run '{hook}' failed with exit code {code}")
            logger.error(problems[-1])
    return problems
