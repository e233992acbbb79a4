"""What a child forked by the fork server does to become the job: ``scenario_execution`` as a fresh process would run.

A child of :mod:`executor.batch.fork_server` (forked for a request, or a spare given one) starts as
a copy of the warm server. Before the command runs it takes the job's own session, standard streams
(from ``/dev/null`` and into the job's output), working directory, environment and signal handling;
after it, it ends as an interpreter ends (threads joined, ``atexit`` functions run, streams flushed)
and exits with the status a launched command would have. Standard library only, as the server.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Callable
from typing import TextIO

#: Signals the server and its children hold back (blocked, so kept pending, never lost) until a job's
#: command runs: a cancel or timeout sent to a job right after its fork, or to a spare's job while
#: the spare warms up, reaches it (the probe must neither swallow nor die of them).
HELD_BACK = {signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT}

#: ``prctl``'s option that asks the kernel for a signal when the process's parent ends.
_PR_SET_PDEATHSIG = 1


def _load_prctl() -> Callable[..., int] | None:
    """libc's ``prctl`` (Linux), loaded once in the server so that no forked child pays for ``ctypes``.

    The modules the lookup imported are taken out of ``sys.modules`` again (the function keeps libc
    loaded): a job must import them as a launched process would, a ``ctypes.py`` of its own included.
    """
    if not sys.platform.startswith("linux"):
        return None
    loaded = set(sys.modules)
    try:
        import ctypes

        return ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None
    finally:
        for name in set(sys.modules) - loaded:
            del sys.modules[name]


_PRCTL = _load_prctl()


def die_with_parent(parent: int) -> None:
    """In a child just forked by ``parent`` (a forking process of the server): be killed when it ends.

    The runner kills the jobs of a server that ended, but only those it knows the pid of: one forked
    a moment before its forker was killed (before the forker could say ``started``) would run on
    unseen. The kernel's parent-death signal leaves no such moment; a parent that ended before the
    signal was asked for is seen by the child's new parent, and the child ends at once.
    """
    if _PRCTL is None:
        return
    _PRCTL(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    if os.getppid() != parent:
        os._exit(1)


def _fresh_stdio() -> None:
    """``sys.stdin/stdout/stderr`` on fds 0-2 as a new interpreter makes them (buffering and all):
    stdout block-buffered (line-buffered on a terminal), stderr line-buffered; with
    ``PYTHONUNBUFFERED`` both write straight to the file descriptor, with no buffer in between, so
    nothing written is lost when the job is killed."""
    import io

    unbuffered = bool(os.environ.get("PYTHONUNBUFFERED"))
    old = {name: getattr(sys, name) for name in ("stdin", "stdout", "stderr")}

    def stream(fd: int, like: TextIO) -> io.TextIOWrapper:
        if fd == 0:
            return io.TextIOWrapper(io.BufferedReader(io.FileIO(fd, "r", closefd=False)),
                                    encoding=like.encoding, errors=like.errors)
        raw = io.FileIO(fd, "w", closefd=False)
        if unbuffered:
            return io.TextIOWrapper(raw, encoding=like.encoding, errors=like.errors, write_through=True)
        return io.TextIOWrapper(io.BufferedWriter(raw), encoding=like.encoding, errors=like.errors,
                                line_buffering=fd == 2 or os.isatty(fd))

    for fd, name in ((0, "stdin"), (1, "stdout"), (2, "stderr")):
        fresh = stream(fd, old[name])
        setattr(sys, name, fresh)          # the job's own streams, also as sys.__stdin__ & co.
        setattr(sys, f"__{name}__", fresh)


def _exit_code(exc: SystemExit) -> int:
    """What the interpreter would exit with for ``SystemExit`` (``None`` 0, a text printed and 1)."""
    code = exc.code
    if code is None:
        return 0
    if isinstance(code, int):
        return code & 0xFF
    print(code, file=sys.stderr)
    return 1


def run_child(request: dict, output_fd: int, close_server: Callable[[], None],
              run: Callable[[list[str]], None]) -> None:
    """In the forked child: become the launched command, run it (``run`` with the request's arguments
    after the program name), never return. ``close_server`` closes what the child must not keep of
    the server (its sockets, pipes, other jobs' logs).

    The stop signals (``HELD_BACK``) come blocked from the server (or the spare); they are let
    through once the command is about to run. One that came meanwhile was meant for a job that had
    not begun: the child ends by it at once, silently, as a process killed before it ran would. A
    ``SIGINT`` that comes once the command has ended, while the exit functions run, is let pass.
    """
    code, interrupted = 1, False
    try:
        if os.getpgid(0) != os.getpid():     # a spare made its own session already
            os.setsid()
        close_server()
        for sig in (signal.SIGTERM, signal.SIGCHLD, signal.SIGHUP, signal.SIGQUIT):
            signal.signal(sig, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGPIPE, signal.SIG_IGN)         # as the interpreter sets it at start
        signal.set_wakeup_fd(-1)
        null = os.open(os.devnull, os.O_RDONLY)
        os.dup2(null, 0)
        os.dup2(output_fd, 1)
        os.dup2(output_fd, 2)
        for fd in (null, output_fd):
            if fd > 2:
                os.close(fd)
        os.chdir(request["cwd"] or ".")
        os.environ.update(request["env"])
        _fresh_stdio()
        try:
            for sig in signal.sigpending() & HELD_BACK:    # stopped before it began
                signal.signal(sig, signal.SIG_DFL)
            signal.pthread_sigmask(signal.SIG_UNBLOCK, HELD_BACK)
            run(list(request["argv"][1:]))
            code = 0
        except SystemExit as exc:
            code = _exit_code(exc)
        except BaseException:  # noqa: BLE001 - what the interpreter would print for an uncaught error
            interrupted = isinstance(sys.exc_info()[1], KeyboardInterrupt)
            sys.excepthook(*sys.exc_info())
            code = 1
        # The command has ended: a stop (SIGINT) that comes now would only break off the exit functions
        # with a KeyboardInterrupt traceback in the job's output. It is let pass (by a handler, not
        # SIG_IGN, which a process started meanwhile would inherit); the runner's kill after the grace
        # still ends exit functions that hang.
        signal.signal(signal.SIGINT, _let_pass)
        code = _finalize(code)
    finally:
        if interrupted:                    # as the interpreter ends on an uncaught Ctrl-C: by SIGINT
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGINT)
        os._exit(code)


def _let_pass(_signum: int, _frame: object) -> None:
    """The ``SIGINT`` handler of a job whose command has ended (see :func:`run_child`)."""


def _finalize(code: int) -> int:
    """The end of an interpreter's life, in its order: wait for the threads that are not daemons,
    run the ``atexit`` functions, flush the standard streams. Returns the exit status, 120 when
    stdout cannot be flushed (as the interpreter's own end reports it)."""
    import atexit
    import threading

    try:
        threading._shutdown()              # type: ignore[attr-defined]  # the interpreter's own join
    except BaseException:  # noqa: BLE001 - as the interpreter does: say it, and go on ending
        sys.excepthook(*sys.exc_info())
    atexit._run_exitfuncs()
    try:
        sys.stdout.flush()
    except Exception:  # noqa: BLE001 - the output is gone (a full disk): the status says so
        code = 120
    try:
        sys.stderr.flush()
    except Exception:  # noqa: BLE001, S110 - as the interpreter, a failing stderr is not reported
        pass
    return code
