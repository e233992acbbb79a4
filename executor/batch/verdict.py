"""Judging one attempt: from how the child ended and the test.xml it wrote to a job state and a reason.

A job passes when its process exits 0 and its test.xml has testcases and no failure or error;
``ignore_return_value`` judges by test.xml alone. No readable test.xml, a death by signal, a
non-zero exit although test.xml passed, and a timeout are infrastructure errors (``error`` /
``timeout``) that ``--retries`` may repeat; a scenario that ran and failed is ``failed`` and never
repeated. An attempt that ended without a result because the disk holding its folder is full is
neither: it is ``cancelled`` with :data:`DISK_FULL_REASON` (the batch stops; ``--resume`` runs it again).
"""

from __future__ import annotations

import errno
import os
import stat
from dataclasses import dataclass

from coverage_engine.results.document import Case
from coverage_engine.results.files import COVERAGE_FILE, LOG_FILE, RESULT_FILE
from coverage_engine.results.read import JunitUnreadable, clean_text, has_problem, read_cases
from executor.children.process import ProcessOutcome
from store.jobs import JUNIT_MAX_BYTES, LOG_TAIL_BYTES, JobResult
from store.states import NOT_STARTED_REASON, JobState

#: Largest coverage.json read with a job's result.
COVERAGE_MAX_BYTES = 16 * 1024 * 1024

#: The reason recorded on a job stopped by a full disk; the worker stops the batch when it sees it.
DISK_FULL_REASON = "not finished: no space left on the device holding its folder"

#: Below this many free bytes (or with no free inode) a file system counts as full.
LOW_SPACE_BYTES = 64 * 1024



def out_of_space(folder: str | os.PathLike[str]) -> bool:
    """Whether the file system holding ``folder`` has (next to) no room left for another file."""
    try:
        st = os.statvfs(folder)
    except (OSError, AttributeError):
        return False
    free_blocks = st.f_bfree if os.geteuid() == 0 else st.f_bavail   # root may use the reserved blocks
    return free_blocks * st.f_frsize < LOW_SPACE_BYTES or (st.f_files > 0 and st.f_favail == 0)


@dataclass(frozen=True)
class FileMark:
    """What a file looked like before the attempt, so a stale result from an earlier run is not taken."""

    signature: tuple[int, int, int] | None

    @classmethod
    def of(cls, path: str | os.PathLike[str]) -> FileMark:
        try:
            st = os.stat(path)
        except OSError:
            return cls(None)
        return cls.of_status(st)

    @classmethod
    def of_status(cls, st: os.stat_result) -> FileMark:
        """The mark of a file whose status is at hand (an open file's ``fstat``)."""
        return cls((st.st_mtime_ns, st.st_size, st.st_ino))

    def changed(self, path: str | os.PathLike[str]) -> bool:
        return FileMark.of(path).signature not in (None, self.signature)


class NotARegularFile(OSError):
    """A file a child left that is a symbolic link or not a regular file (never followed, never read)."""


@dataclass(frozen=True)
class ChildFile:
    """What was read of a file a child wrote: its size, and its bytes (the last ``tail`` of them, or the
    whole file; None when it is larger than the reader allowed)."""

    size: int
    data: bytes | None


def read_child_file(path: str | os.PathLike[str], *, limit: int | None = None,
                    tail: int | None = None) -> ChildFile:
    """Read a file a child wrote without following a symbolic link: a child (or anyone who can write into its
    folder) could otherwise make ``test.xml`` point at a secret that the report would carry.

    ``limit``: a larger file is not read (``data`` None). ``tail``: only its last ``tail`` bytes are.
    With plain descriptor calls (open, fstat, one read): a buffered file object costs five more system
    calls, and a batch reads two or three of these files per job.
    """
    read = read_new_child_file(path, None, limit=limit, tail=tail)
    assert read is not None                      # (only a mark makes it None)
    return read


def read_new_child_file(path: str | os.PathLike[str], mark: FileMark | None, *, limit: int | None = None,
                        tail: int | None = None) -> ChildFile | None:
    """:func:`read_child_file`, or None when the file is still the one ``mark`` saw before the attempt (not
    written by it): the open file's own status tells, so a file that is read costs no ``stat`` of its own."""
    # O_NONBLOCK: a FIFO left in the file's place must not hold the batch in open() (it is refused below)
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
    try:
        status = os.fstat(fd)
        if mark is not None and FileMark.of_status(status) == mark:
            return None
        if not stat.S_ISREG(status.st_mode):
            raise NotARegularFile(f"{os.path.basename(path)} is not a regular file")
        size = status.st_size
        if limit is not None and size > limit:
            return ChildFile(size, None)
        start = max(0, size - tail) if tail is not None else 0
        return ChildFile(size, _read_from(fd, start, size - start))
    finally:
        os.close(fd)


def _read_from(fd: int, start: int, length: int) -> bytes:
    """``length`` bytes from ``start`` (fewer when the file is shorter by now): the file as it was when its
    size was looked at, even if it grows meanwhile."""
    data = os.pread(fd, length, start)
    while 0 < len(data) < length:
        more = os.pread(fd, length - len(data), start + len(data))
        if not more:
            break
        data += more
    return data


def log_tail(path: str | os.PathLike[str], limit: int = LOG_TAIL_BYTES) -> str:
    """The last ``limit`` bytes of a log, decoded leniently and cleaned for XML and the store."""
    try:
        read = read_child_file(path, tail=limit)
    except OSError:
        return ""
    text = (read.data or b"").decode("utf-8", errors="replace")
    if read.size > limit:
        text = "[… earlier output in log.txt]\n" + text.split("\n", 1)[-1]
    return clean_text(text)


#: Why an attempt's test.xml is not taken when the attempt wrote none (or left an earlier one as it was).
NOT_WRITTEN = "no test.xml written"


def read_result(path: str | os.PathLike[str], mark: FileMark) -> tuple[str | None, list[Case], str | None]:
    """The test.xml the attempt wrote (text or None, its testcases) and why it cannot be used (None if it can)."""
    try:
        read = read_new_child_file(path, mark, limit=JUNIT_MAX_BYTES)
    except OSError as exc:
        if not mark.changed(path):               # none there, or one left as it was (a link is followed here)
            return None, [], NOT_WRITTEN
        if exc.errno == errno.ELOOP or os.path.islink(path):     # O_NOFOLLOW met a link (ELOOP on Linux)
            return None, [], "test.xml is a symbolic link: not followed (a result must be a file in the job's folder)"
        return None, [], f"cannot read test.xml: {exc.strerror or exc}"
    if read is None:
        return None, [], NOT_WRITTEN
    if read.data is None:
        return None, [], f"test.xml is {read.size} bytes, more than the {JUNIT_MAX_BYTES} bytes kept"
    text = read.data.decode("utf-8", errors="replace")
    try:
        cases = read_cases(text)
    except JunitUnreadable as exc:
        return clean_text(text), [], str(exc)
    if not cases:
        return clean_text(text), [], "test.xml holds no testcase"
    return clean_text(text), cases, None


def read_coverage(path: str | os.PathLike[str], mark: FileMark) -> str | None:
    """COVERAGE HOOK — the one place a job's ``coverage.json`` is read, beside its ``test.xml``.

    The text the attempt wrote (None when it wrote none, or more than :data:`COVERAGE_MAX_BYTES`), handed
    on with the result (:attr:`JobResult.coverage_json`); the coverage model records it with the job.
    """
    try:
        read = read_new_child_file(path, mark, limit=COVERAGE_MAX_BYTES)
    except OSError:
        return None
    return None if read is None or read.data is None else read.data.decode("utf-8", errors="replace")


def judge(outcome: ProcessOutcome, output_dir: str | os.PathLike[str], mark: FileMark, *,
          ignore_return_value: bool = False, timeout: float | None = None,
          coverage_mark: FileMark | None = None) -> JobResult:
    """The result of one attempt, ready to be written to the store (with its coverage.json, if any, and
    its log's tail where the verdict is shown with it: not for a pass, whose log is not read)."""
    folder = os.fspath(output_dir)
    xml_text, cases, unreadable = read_result(os.path.join(folder, RESULT_FILE), mark)
    rc = outcome.returncode
    if outcome.cancelled:
        status, reason = JobState.CANCELLED, "cancelled"
    elif outcome.timed_out:
        status, reason = JobState.TIMEOUT, f"timed out after {timeout:g} s" if timeout else "timed out"
    elif unreadable is not None:
        status = JobState.ERROR
        ended = f"killed by {outcome.signal_name}" if outcome.signal_name else f"exit code {rc}"
        reason = f"{unreadable} ({ended})"
    elif has_problem(cases):
        status, reason = JobState.FAILED, "test.xml reports a failure"
    elif outcome.signal_name and not ignore_return_value:
        status, reason = JobState.ERROR, f"killed by {outcome.signal_name} although its test.xml passed"
    elif rc != 0 and not ignore_return_value:
        status, reason = JobState.ERROR, f"exit code {rc} although its test.xml passed"
    else:
        status, reason = JobState.PASSED, None
    if status is JobState.ERROR and (outcome.disk_full or out_of_space(folder)):
        status, reason = JobState.CANCELLED, DISK_FULL_REASON
    log = os.path.join(folder, LOG_FILE)
    return JobResult(status=status, exit_code=rc, started_at=outcome.started_at,
                     finished_at=outcome.finished_at, reason=reason, junit_xml=xml_text,
                     log_tail=None if status is JobState.PASSED else log_tail(log), output_dir=folder, log_path=log,
                     coverage_json=None if coverage_mark is None else read_coverage(
                         os.path.join(folder, COVERAGE_FILE), coverage_mark))


def never_started(result: JobResult) -> bool:
    """Whether an attempt ended before its child started: cancelled (a stop) while it waited for its
    turn or at the fork server, or its fork server ended first. Its job goes back to the queue; nothing
    of it is recorded."""
    return result.status is JobState.CANCELLED and result.reason == NOT_STARTED_REASON


def launch_failure(output_dir: str | os.PathLike[str], started_at: float, finished_at: float,
                   message: str) -> JobResult:
    """The result of an attempt whose command could not even be started."""
    folder = os.fspath(output_dir)
    log = os.path.join(folder, LOG_FILE)
    return JobResult(status=JobState.ERROR, exit_code=None, started_at=started_at, finished_at=finished_at,
                     reason=message, log_tail=log_tail(log), output_dir=folder, log_path=log)


def disk_full_result(output_dir: str | os.PathLike[str], started_at: float, finished_at: float) -> JobResult:
    """The result of an attempt the full disk kept from running or from writing its result."""
    folder = os.fspath(output_dir)
    log = os.path.join(folder, LOG_FILE)
    return JobResult(status=JobState.CANCELLED, exit_code=None, started_at=started_at, finished_at=finished_at,
                     reason=DISK_FULL_REASON, log_tail=log_tail(log), output_dir=folder, log_path=log)
