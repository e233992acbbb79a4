"""One child process in its own process group: its log file, its timeout and cancellation.

Used for batch jobs and for ``--post-run`` hooks. The child's stdout and stderr go straight into its
log (the kernel writes them, so nothing is lost when the child or this process dies); with ``echo``
they pass through a pipe and are copied to the log and to the terminal as they arrive; without a log
the child shares this process's terminal. A timeout or a cancel signals the whole process group, then
kills it after a grace period, which the rest of the group gets even when the child itself ends
sooner (a wrapper script that dies at once must not cut its scenario's report short); whatever is
left of the group when the child exits is killed too.
"""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import IO, Any, BinaryIO, Protocol

from executor.children.spawn import SpawnedProcess, can_spawn_logged, spawn_logged

_CHUNK = 64 * 1024

#: Errors that mean "the disk is full", whoever met them.
DISK_FULL_ERRNOS = frozenset({errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)})


def disk_full(exc: BaseException) -> bool:
    """Whether ``exc`` says the disk (or the user's quota) is full."""
    return isinstance(exc, OSError) and exc.errno in DISK_FULL_ERRNOS


class StartTicket:
    """A start that a launcher may hold back while its slots are busy; :meth:`withdraw` gives it up.

    The launcher says how to take its request back (:meth:`on_withdraw`) before the request goes
    out, and that it went (:meth:`sent`: ``on_sent`` is called, e.g. to let the next job's request
    go); a withdrawal that comes first is remembered, and the launcher then never sends the request.
    """

    def __init__(self, on_sent: Callable[[], None] | None = None) -> None:
        self._lock = threading.Lock()
        self._take_back: Callable[[], None] | None = None
        self._on_sent = on_sent
        self.withdrawn = False

    def sent(self) -> None:
        """The launcher has sent the request (it may still hold the start back)."""
        if self._on_sent is not None:
            self._on_sent()

    def on_withdraw(self, take_back: Callable[[], None]) -> bool:
        """Register how to take the request back; False when it was withdrawn already (do not send it)."""
        with self._lock:
            if self.withdrawn:
                return False
            self._take_back = take_back
            return True

    def withdraw(self) -> None:
        with self._lock:
            self.withdrawn = True
            take_back, self._take_back = self._take_back, None
        if take_back is not None:
            take_back()


class Launcher(Protocol):
    """Starts a command some other way than ``exec`` (the built-in runner forks it from a warm server)."""

    def spawn(self, argv: Sequence[str], *, cwd: str | None, environment: Mapping[str, str],
              output_fd: int | None = None, stdout: BinaryIO | None = None, ticket: StartTicket | None = None,
              log_path: str | None = None, append: bool = False, log_folder: tuple[str, str] | None = None) -> Any:
        """Start ``argv`` in its own session with stdout and stderr on ``output_fd``, or on the file
        ``log_path`` that the launcher opens itself (truncated, or appended to; its folder made first
        when ``log_folder`` names the root it must lie in and the root's real path); a Popen-like object,
        or None when ``ticket`` was withdrawn before the start (it may wait for a free slot)."""


@dataclass(frozen=True)
class ProcessOutcome:
    """How a child process ended."""

    returncode: int | None
    started_at: float
    finished_at: float
    timed_out: bool = False
    cancelled: bool = False
    #: Copying the child's output to its log met a full disk (the rest of the output was dropped).
    disk_full: bool = False

    @property
    def signal_name(self) -> str | None:
        """Name of the signal that ended the child, if one did."""
        if self.returncode is None or self.returncode >= 0:
            return None
        try:
            return signal.Signals(-self.returncode).name
        except ValueError:
            return f"signal {-self.returncode}"


def kill_group(pgid: int, sig: int = signal.SIGKILL) -> bool:
    """Send ``sig`` to process group ``pgid``; False if the group is gone."""
    try:
        os.killpg(pgid, sig)
        return True
    except ProcessLookupError:
        return False
    except PermissionError:
        return False


def kill_orphan(pid: int, mark: str | None = None) -> None:
    """SIGKILL to a job whose parent (the fork server) is gone: to its group, and, when there is no such
    group (a child forked a moment before may not lead one yet), to the process itself if it carries
    ``mark`` (``RUNNER_ENV=<worker id>``, which every process of that server has) in its environment:
    a process id that was reused meanwhile belongs to a process without it."""
    if kill_group(pid) or mark is None:
        return
    try:
        with open(f"/proc/{pid}/environ", "rb") as handle:
            if mark.encode() not in handle.read().split(b"\0"):
                return
        os.kill(pid, signal.SIGKILL)
    except OSError:
        pass


def process_alive(pid: int | None) -> bool:
    """Whether a process with this id exists on this host and is not a zombie."""
    if not pid:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        with open(f"/proc/{pid}/stat", "rb") as handle:
            return handle.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except (OSError, IndexError):
        return True


def group_alive(pgid: int) -> bool:
    """Whether any process of group ``pgid`` is left (zombies count until reaped)."""
    try:
        os.killpg(pgid, 0)
        return True
    except ProcessLookupError:
        return False
    except PermissionError:
        return True


#: Environment variable set for every job's child: ``<job id>.<attempt>``; it also marks the process group.
JOB_ENV = "SCENARIO_BATCH_JOB"

#: Environment variable set for every process a runner starts: the runner's worker id (see the watchdog).
RUNNER_ENV = "SCENARIO_BATCH_RUNNER"


def end_orphan_group(pgid: int, marker: str, runner: str | None = None) -> bool:
    """SIGKILL process group ``pgid`` if one of its processes carries ``JOB_ENV=marker`` (or, for a job of
    the built-in runner, whose marker is set after the fork, ``RUNNER_ENV=runner``).

    A recorded process id may have been reused by an unrelated process by the time a dead runner's
    jobs are taken back, so the group is ended only when it provably belongs to that job's attempt
    (or to the dead runner: its worker id is unique).
    """
    wanted = {f"{JOB_ENV}={marker}".encode()}
    if runner:
        wanted.add(f"{RUNNER_ENV}={runner}".encode())
    try:
        entries = os.listdir("/proc")
    except OSError:
        return False
    for entry in entries:
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as handle:
                fields = handle.read().rsplit(b")", 1)[1].split()
            if int(fields[2]) != pgid:
                continue
            with open(f"/proc/{entry}/environ", "rb") as handle:
                if wanted.intersection(handle.read().split(b"\0")):
                    return kill_group(pgid)
        except (OSError, IndexError, ValueError):
            continue
    return False


class ChildProcess:
    """Start a command in a new session and wait for it; ``cancel`` may be called from another thread."""

    def __init__(self, argv: Sequence[str], log_path: str | None, *, cwd: str | None = None,
                 timeout: float | None = None, grace: float = 5.0, echo: BinaryIO | None = None,
                 marker: str | None = None, environment: Mapping[str, str] | None = None,
                 append: bool = False, launcher: Launcher | None = None,
                 on_sent: Callable[[], None] | None = None, log_folder: tuple[str, str] | None = None) -> None:
        self.argv = list(argv)
        self.log_path = log_path               # None: stdin, stdout and stderr are this process's
        self.append = append
        self.cwd = cwd
        self.timeout = timeout
        self.grace = grace
        self.echo = echo
        self.launcher = launcher               # None: exec argv; else the launcher forks it (built-in runner)
        self.on_sent = on_sent                 # told when the launcher has the request (see StartTicket)
        self.log_folder = log_folder           # the launcher makes the log's folder: (root, its real path)
        self.extra_env = dict(environment or {})
        if marker is not None:
            self.extra_env[JOB_ENV] = marker
        self.proc: subprocess.Popen[bytes] | SpawnedProcess | None = None
        self._lock = threading.Lock()
        self._timers: list[threading.Timer] = []
        self._timed_out = False
        self._cancelled = False
        self._log_error: OSError | None = None
        self._started_at = 0.0
        self._kill_at: float | None = None     # monotonic time of the SIGKILL a timeout or cancel arranged
        self._ticket: StartTicket | None = None  # a launcher's start not begun yet (cancel withdraws it)
        self._grace_asked: float | None = None   # the grace of a cancel that came while the start was held

    @property
    def pid(self) -> int | None:
        return None if self.proc is None else self.proc.pid

    def start(self) -> int | None:
        """Spawn the child (no shell, own process group); raises OSError when it cannot be started.

        Returns its process id, or None without starting it when :meth:`cancel` came first. A
        launcher may hold the start back until one of its slots is free; the wait is not the child's
        time (its start time and timeout count from the start), and a cancel meanwhile withdraws it.
        """
        if self.launcher is not None and self.log_path is not None:
            return self._start_launched()
        self._started_at = time.time()
        with self._lock:
            if self._cancelled:
                return None
            if self.log_path is None:
                self.proc = self._spawn(None, None)
            elif self.echo is None and can_spawn_logged(self.cwd):     # the child opens its log
                self.proc = spawn_logged(self.argv, self.log_path, append=self.append,
                                         extra_environment=self.extra_env)
            else:
                with open(self.log_path, "ab" if self.append else "wb") as log:
                    self.proc = self._spawn(subprocess.DEVNULL,
                                            subprocess.PIPE if self.echo is not None else log)
            if self.timeout is not None:
                self._arm_locked(self.timeout, self._on_timeout)
            return self.proc.pid

    def _spawn(self, stdin: int | None, stdout: int | IO[bytes] | None) -> subprocess.Popen[bytes]:
        return subprocess.Popen(
            self.argv, cwd=self.cwd, stdin=stdin, stdout=stdout,
            stderr=None if stdout is None else subprocess.STDOUT,
            env={**os.environ, **self.extra_env} if self.extra_env else None,  # (a fork inherits os.environ)
            start_new_session=True, close_fds=True)

    def _start_launched(self) -> int | None:
        """:meth:`start` through the launcher, which may hold it back: this lock is not held meanwhile."""
        with self._lock:
            if self._cancelled:
                return None
            ticket = self._ticket = StartTicket(self.on_sent)
        assert self.launcher is not None and self.log_path is not None
        if self.echo is None:                    # the launcher opens the log: no file made here
            proc = self.launcher.spawn(self.argv, cwd=self.cwd, environment=self.extra_env, ticket=ticket,
                                       log_path=os.path.abspath(self.log_path), append=self.append,
                                       log_folder=self.log_folder)
        else:
            proc = self._fork_echoing(ticket)
        self._started_at = time.time()
        with self._lock:
            self._ticket = None
            if proc is None:                     # withdrawn by a cancel before it started
                return None
            self.proc = proc
            if self.timeout is not None:
                self._arm_locked(self.timeout, self._on_timeout)
            if self._cancelled:                  # the cancel came too late to withdraw it: stop it now
                self._cancel_locked(self.grace if self._grace_asked is None else self._grace_asked)
            return proc.pid

    def _fork_echoing(self, ticket: StartTicket) -> Any:
        """Have the launcher fork the command, its output going to a pipe (copied to the log and the echo)."""
        assert self.launcher is not None and self.log_path is not None
        with open(self.log_path, "ab" if self.append else "wb"):
            pass                                 # made now, as the log of a launched command is
        read_end, write_end = os.pipe()
        stdout = os.fdopen(read_end, "rb")
        try:
            proc = self.launcher.spawn(self.argv, cwd=self.cwd, environment=self.extra_env,
                                       output_fd=write_end, stdout=stdout, ticket=ticket)
        except BaseException:
            stdout.close()
            raise
        finally:
            os.close(write_end)
        if proc is None:
            stdout.close()
        return proc

    def wait(self) -> ProcessOutcome:
        """Block until the child exits (copying its output when echoing); end what is left of its group.

        A child that was cancelled before it started ends at once as cancelled, with no return code.
        """
        if self.proc is None:
            assert self._cancelled, "start() first"
            now = time.time()
            return ProcessOutcome(returncode=None, started_at=now, finished_at=now, cancelled=True)
        copier = None
        if self.echo is not None:
            copier = threading.Thread(target=self._copy, name=f"log-{self.proc.pid}", daemon=True)
            copier.start()
        returncode = self.proc.wait()
        finished = time.time()
        with self._lock:
            deadline = self._kill_at
        if deadline is not None:               # signalled: the rest of the group gets its grace period too
            while time.monotonic() < deadline and group_alive(self.proc.pid):
                time.sleep(0.02)
        with self._lock:
            for timer in self._timers:
                timer.cancel()
            self._timers.clear()
            kill_group(self.proc.pid)          # grandchildren left behind die with the job
        if copier is not None:
            copier.join(timeout=5.0)
        error = self._log_error
        return ProcessOutcome(returncode=returncode, started_at=self._started_at, finished_at=finished,
                              timed_out=self._timed_out, cancelled=self._cancelled and not self._timed_out,
                              disk_full=error is not None and disk_full(error))

    def cancel(self, grace: float | None = None) -> None:
        """Ask the child's group to stop (SIGINT), kill it after ``grace`` seconds (0: at once)."""
        grace = self.grace if grace is None else grace
        with self._lock:
            self._cancelled = True
            if self.proc is None:
                ticket = self._ticket            # a start held back by the launcher: take it back
                if self._grace_asked is None or grace < self._grace_asked:
                    self._grace_asked = grace
            else:
                self._cancel_locked(grace)
                return
        if ticket is not None:
            ticket.withdraw()

    def _signal_locked(self, sig: int) -> None:
        """``sig`` to the child's group; to the child itself when it has no group yet (a job forked an
        instant ago has not made its own session: the signal waits, blocked, until it has)."""
        assert self.proc is not None
        if not kill_group(self.proc.pid, sig) and self.launcher is not None and self.proc.returncode is None:
            try:
                os.kill(self.proc.pid, sig)
            except OSError:
                pass

    def _cancel_locked(self, grace: float) -> None:
        """SIGINT to the child's group and SIGKILL after ``grace`` (at once when it is 0); holds the lock."""
        assert self.proc is not None
        if grace <= 0:
            self._kill_at = time.monotonic()
            self._signal_locked(signal.SIGKILL)
            return
        if self.proc.returncode is not None:
            return
        self._signal_locked(signal.SIGINT)
        self._arm_kill_locked(grace)

    def _arm_locked(self, delay: float, action: Callable[[], None]) -> None:
        timer = threading.Timer(delay, action)
        timer.daemon = True
        self._timers.append(timer)
        timer.start()

    def _arm_kill_locked(self, grace: float) -> None:
        """SIGKILL the group ``grace`` seconds from now (or sooner, if an earlier kill is due)."""
        deadline = time.monotonic() + grace
        if self._kill_at is None or deadline < self._kill_at:
            self._kill_at = deadline
            self._arm_locked(grace, self._on_grace_over)

    def _on_timeout(self) -> None:
        with self._lock:
            if self.proc is None or self.proc.returncode is not None:
                return
            self._timed_out = True
            self._signal_locked(signal.SIGTERM)
            self._arm_kill_locked(self.grace)

    def _on_grace_over(self) -> None:
        with self._lock:
            if self.proc is not None:
                self._signal_locked(signal.SIGKILL)

    def _copy(self) -> None:
        assert self.proc is not None and self.proc.stdout is not None and self.echo is not None
        stream = self.proc.stdout
        assert self.log_path is not None
        log: BinaryIO | None = None
        try:
            log = open(self.log_path, "ab")
        except OSError as exc:
            self._log_error = exc
        while True:
            data = stream.read1(_CHUNK) if hasattr(stream, "read1") else stream.read(_CHUNK)
            if not data:
                break
            if log is not None:
                try:
                    log.write(data)
                    log.flush()
                except OSError as exc:   # a full disk: keep draining the pipe (the child must not block)
                    self._log_error = exc
                    _close_quietly(log)
                    log = None
            try:
                self.echo.write(data)
                self.echo.flush()
            except (OSError, ValueError):
                pass
        _close_quietly(log)
        stream.close()


def _close_quietly(handle: BinaryIO | None) -> None:
    """Close ``handle`` (if any), ignoring the error a full disk gives when the last bytes are flushed."""
    if handle is not None:
        try:
            handle.close()
        except OSError:
            pass
