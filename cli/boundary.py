"""The one error boundary of every command: exceptions become a message on stderr and an exit code.

Exit codes, the same for all commands: 0 success · 1 a runtime error (bad input, a file or store
problem) or a failed result · 2 a usage error (click's own, or one the command declares) · 130
interrupted (Ctrl-C; SIGTERM where the command maps it). Every error a user can cause is a
:class:`~coverage_engine.errors.UserError` (the scenario's, the store's, the batch's, the command line's),
and only here does one become a message: ``file:line:col: error: …`` with the source line and a caret
where it has a place, ``file: error: …`` for a whole file, ``error: …`` otherwise; exit 2 when it is a
malformed command line (:attr:`~coverage_engine.errors.UserError.usage`), else 1. An :class:`OSError`
says ``error: <reason>: <file>``. A command run by scripts on many hosts
(``scenario_batch_execution``) asks for one line per message, prefixed by its name. A traceback is
shown only with ``-d/--debug``, which the shared option reports here while the command line is parsed
(:func:`cli.options.debug_option`); an error of ours that no one expected says "internal error".
"""

from __future__ import annotations

import atexit
import gc
import sys
from collections.abc import Callable, Sequence
from typing import NoReturn

import click

from coverage_engine.errors import UserError
from coverage_engine.printable import printable_lines

EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


def _collect_once_then_freeze() -> None:
    gc.collect()          # what is garbage by now is finalized, as the ending interpreter would have done
    gc.freeze()           # what is still held is never scanned again while the modules are torn down


def end_with_one_collection() -> None:
    """Have the ending interpreter collect its garbage once, not again and again over every object left.

    An ending interpreter clears its modules and collects garbage over every object still held,
    SQLAlchemy's, click's and ours, hundreds of thousands, more than once. Measured on this project's
    2-core VM: 0.1 s of CPU and of wall time at the end of a batch process (a fifth of a one-job batch's
    own CPU); one collection, done here instead, costs 0.03 s of it. Registered as an ``atexit``
    function as the command starts, it runs after those registered while the command ran and before
    those registered earlier (``logging``'s, which flushes its handlers by itself): it finalizes what
    is garbage by then, and ``gc.freeze`` leaves everything still held out of the collections that
    follow. An object still held at that moment (by a module, a cache) is freed by its reference count
    as the modules are cleared, or not at all: a reference cycle among such objects no longer gets its
    ``__del__``, nor its buffered file a flush. So only a command that runs no one else's Python in its
    own process (no plugin, no external method, no scenario folder's module) asks for this:
    ``Boundary(..., quick_end=True)``. A test that runs such a command in its own process freezes that
    process as it ends.
    """
    atexit.unregister(_collect_once_then_freeze)
    atexit.register(_collect_once_then_freeze)


class Boundary:
    """Runs one click command and maps whatever escapes it; ``prog`` is the name in usage texts.

    ``one_line_name``: print every message on one line as ``<name>: error: …``. ``quick_end``: the
    command runs no one else's Python in its process, which may then end with one garbage collection
    (:func:`end_with_one_collection`).
    """

    def __init__(self, prog: str, *, one_line_name: str | None = None, quick_end: bool = False) -> None:
        self.prog = prog
        self.one_line_name = one_line_name
        self.quick_end = quick_end
        self.tracebacks = False

    def show_tracebacks(self) -> None:
        """Called by ``-d/--debug`` while the command line is parsed."""
        self.tracebacks = True

    def main(self, command: click.Command, args: Sequence[str] | None = None) -> NoReturn:
        """Run ``command`` with ``args`` (default: the process's) and exit with its code."""
        if self.quick_end:
            end_with_one_collection()
        sys.exit(self.run(command, args))

    def report(self, exc: Exception) -> int:
        """Say one error of a command that goes on after it (one of several input files); its exit code."""
        if isinstance(exc, UserError):
            self._say_user_error(exc)
        else:
            self._say(f"error: {exc}")
        return EXIT_FAILED

    def run(self, command: click.Command, args: Sequence[str] | None = None) -> int:
        """Run ``command``; returns its exit code (the callback's int, or the code of what escaped)."""
        argv = list(sys.argv[1:] if args is None else args)
        return self.guarded(lambda: command.main(argv, prog_name=self.prog, standalone_mode=False, obj=self))

    def guarded(self, call: Callable[[], object]) -> int:
        """Run ``call`` (a command, or a command's callback with its options given) behind this boundary;
        a Ctrl-C that comes while an error is being reported ends it as interrupted, with no traceback."""
        try:
            return self._guarded(call)
        except KeyboardInterrupt:
            self._say("interrupted")
            return EXIT_INTERRUPTED

    def _guarded(self, call: Callable[[], object]) -> int:
        try:
            code = call()
        except (click.exceptions.Abort, KeyboardInterrupt):
            self._say("interrupted")
            return EXIT_INTERRUPTED
        except click.ClickException as exc:
            if self.one_line_name is None:
                import io

                shown = io.StringIO()                    # (a name from the command line, escaped)
                exc.show(file=shown)
                click.echo(printable_lines(shown.getvalue().rstrip("\n")), err=True)
            else:
                self._say(f"error: {exc.format_message()}")
            return exc.exit_code
        except UserError as exc:
            if not exc.usage:
                self._traceback()
            self._say_user_error(exc)
            return EXIT_USAGE if exc.usage else EXIT_FAILED
        except OSError as exc:
            self._traceback()
            self._say(f"error: {exc.strerror or exc}: {exc.filename}" if exc.filename else f"error: {exc}")
            return EXIT_FAILED
        except Exception as exc:  # noqa: BLE001 - the last line of defence: a bug of ours, no traceback without -d
            self._traceback()
            self._say(f"error: internal error: {type(exc).__name__}: {exc} (run with -d for the traceback)")
            return EXIT_FAILED
        return code if isinstance(code, int) else 0

    def _traceback(self) -> None:
        if self.tracebacks:
            import traceback  # only here: importing it costs a millisecond of every start

            traceback.print_exc()

    def _say_user_error(self, exc: UserError) -> None:
        self._say(exc.render() if self.one_line_name is None else exc.located())

    def _say(self, message: str) -> None:
        message = printable_lines(message)       # names and source lines come from files: never raw escapes
        if self.one_line_name is not None:
            # driver errors span several lines and SQLAlchemy adds a link line: one line for logs
            lines = [line.strip() for line in message.splitlines()
                     if line.strip() and not line.startswith("(Background on this error")]
            message = f"{self.one_line_name}: {' '.join(lines)}"
        click.echo(message, err=True)
