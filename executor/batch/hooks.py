"""``--post-run`` hooks: after each job, ``CMD <job output folder>``; failures are reported, never fatal.

Each hook runs without a shell (its text split like a shell would), in its own process group, with a
10-minute limit; its output is appended to ``post_run.log`` in the job's folder.
"""

from __future__ import annotations

import shlex
from collections.abc import Sequence
from pathlib import Path

from executor.batch.process import ChildProcess

HOOK_TIMEOUT = 600.0
HOOK_LOG = "post_run.log"


def run_post_hooks(hooks: Sequence[str], output_dir: Path, cwd: str | None = None) -> list[str]:
    """Run every hook on ``output_dir`` in order; returns one message per hook that failed."""
    problems = []
    for hook in hooks:
        try:
            argv = shlex.split(hook) + [str(output_dir)]
        except ValueError as exc:
            problems.append(f"post-run {hook!r}: {exc}")
            continue
        log_path = output_dir / f".{HOOK_LOG}.part"
        child = ChildProcess(argv, str(log_path), cwd=cwd, timeout=HOOK_TIMEOUT, grace=5.0)
        try:
            child.start()
        except OSError as exc:
            problems.append(f"post-run {hook!r} could not start: {exc.strerror or exc}")
            continue
        outcome = child.wait()
        with open(output_dir / HOOK_LOG, "ab") as log, open(log_path, "rb") as part:
            log.write(f"$ {shlex.join(argv)}\n".encode())
            log.write(part.read())
        log_path.unlink(missing_ok=True)
        if outcome.timed_out:
            problems.append(f"post-run {hook!r} timed out after {HOOK_TIMEOUT:g} s")
        elif outcome.returncode != 0:
            problems.append(f"post-run {hook!r} failed with exit code {outcome.returncode}")
    return problems
