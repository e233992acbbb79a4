"""What people see while a batch runs: a rich progress display on a terminal, plain lines otherwise.

The worker loop calls a :class:`Reporter`; it never prints itself. Plain output is one line per
finished job (``[3/10] passed  a_ok  0.52 s``; every job that ends gets the next number, a cancelled
one too, so after Ctrl-C the numbers still count the jobs that ended; a retry line has none), used
when stdout is not a terminal or ``TERM=dumb``, or with ``-j 1`` (where the child's own output is
shown live instead of a progress bar). ``NO_COLOR`` keeps the display and drops its colours.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, TextIO

from executor.output.terminal import printable, wants_rich
from store.jobs import Job, JobResult
from store.states import JobState

if TYPE_CHECKING:
    from rich.progress import TaskID


class Reporter:
    """Receives the events of a batch; the base class prints nothing."""

    def begin(self, total: int | None, done: int = 0) -> None:
        """The batch starts with ``total`` jobs (None when unknown), ``done`` of them already finished."""

    def job_started(self, job: Job) -> None:
        """An attempt of ``job`` started."""

    def job_finished(self, job: Job, result: JobResult, *, retrying: bool = False) -> None:
        """An attempt of ``job`` ended with ``result``; ``retrying`` when the job was queued again."""

    def warn(self, text: str) -> None:
        """Something went wrong that does not stop the batch."""

    def end(self) -> None:
        """The batch is over (or interrupted); release the display."""


def _line(prefix: str, job: Job, result: JobResult, retrying: bool) -> str:
    verdict = "retry" if retrying else result.status.value
    text = f"{prefix}{verdict:<9} {printable(job.name)}  {result.duration:.2f} s"
    if result.status is not JobState.PASSED and result.reason:
        text += f"  ({printable(result.reason)})"
    return text


class PlainReporter(Reporter):
    """One line per finished job on ``stream``; warnings on stderr."""

    def __init__(self, stream: TextIO | None = None) -> None:
        self.stream = stream or sys.stdout
        self.total: int | None = None
        self.done = 0

    def begin(self, total: int | None, done: int = 0) -> None:
        self.total, self.done = total, done

    def job_finished(self, job: Job, result: JobResult, *, retrying: bool = False) -> None:
        """Number the job that reached an end here (a verdict, or cancelled); a retry line has no number."""
        prefix = f"[{self.done + 1}/{self.total}] " if self.total else f"[{self.done + 1}] "
        if retrying:
            prefix = " " * len(prefix)
        else:
            self.done += 1
        # one write for the line and its end: an echoed child's output (-j 1, another thread) cannot
        # land between them, as it could between print()'s two writes to an unbuffered stream
        self.stream.write(_line(prefix, job, result, retrying) + "\n")
        self.stream.flush()

    def warn(self, text: str) -> None:
        print(f"warning: {text}", file=sys.stderr, flush=True)


class RichReporter(Reporter):
    """A live progress bar with counts of passed, failed and running jobs and an ETA."""

    def __init__(self) -> None:
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

        self.console = Console()
        self.progress = Progress(
            TextColumn("[bold]batch"), BarColumn(), MofNCompleteColumn(),
            TextColumn("[green]{task.fields[passed]} passed"), TextColumn("[red]{task.fields[failed]} failed"),
            TextColumn("[cyan]{task.fields[running]} running"), TimeRemainingColumn(),
            console=self.console, transient=False)
        self.task: TaskID | None = None
        self.passed = self.failed = self.running = 0

    def begin(self, total: int | None, done: int = 0) -> None:
        self.progress.start()
        self.task = self.progress.add_task("batch", total=total, completed=done, passed=0, failed=0, running=0)

    def _update(self, advance: int = 0) -> None:
        if self.task is not None:
            self.progress.update(self.task, advance=advance, passed=self.passed, failed=self.failed,
                                 running=self.running)

    def job_started(self, job: Job) -> None:
        self.running += 1
        self._update()

    def job_finished(self, job: Job, result: JobResult, *, retrying: bool = False) -> None:
        self.running = max(0, self.running - 1)
        finished = not retrying and result.status is not JobState.CANCELLED
        if finished and result.status is JobState.PASSED:
            self.passed += 1
        elif finished:
            self.failed += 1
        if result.status is not JobState.PASSED:
            self.progress.console.print(_line("", job, result, retrying), markup=False, highlight=False)
        self._update(advance=1 if finished else 0)

    def warn(self, text: str) -> None:
        self.progress.console.print(f"warning: {text}", markup=False, style="yellow")

    def end(self) -> None:
        self.progress.stop()


def make_reporter(slots: int) -> Reporter:
    """The reporter for a run with ``slots`` parallel jobs on the current stdout."""
    if slots > 1 and wants_rich():
        return RichReporter()
    return PlainReporter()

