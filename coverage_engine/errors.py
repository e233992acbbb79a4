"""The one exception tree of every error a user can cause, rooted at :class:`UserError`.

A user error carries where it is when that is known (a :class:`~coverage_engine.location.Location`: a
line and column of a file, or :meth:`~coverage_engine.location.Location.whole_file`) and whether it is a
malformed command line (:attr:`UserError.usage`). ``cli/boundary.py`` alone turns one into
``file:line:col: error: message`` plus the source line and a caret, and into the exit code; nothing
below ``cli/`` prints or exits. The errors in what the user wrote (a scenario, library, parameter or
results file) are :class:`OscError`; the other packages root theirs here too (``store``'s
``StoreError``, ``executor``'s ``BatchError`` and ``UsageProblem``).
"""

from __future__ import annotations

from collections.abc import Callable

from coverage_engine.location import Location
from coverage_engine.printable import clipped, printable


class UserError(Exception):
    """An error the user can fix: in what they wrote, in the files or store they named, or in how they
    called a command (each subclass's docstring is its default message). ``str()`` is the message alone,
    as for any exception, so one can be wrapped in another's message."""

    #: A malformed command line: the command exits 2, as for a bad option, rather than 1.
    usage = False

    def __init__(self, message: str | None = None, location: Location | None = None,
                 source_line: str | None = None, hint: str | None = None) -> None:
        self.message = message or (self.__doc__ or "error").strip().splitlines()[0]
        self.location = location
        self.source_line = source_line
        self.hint = hint
        super().__init__(self.message)

    def __str__(self) -> str:
        return self.message

    def located(self, place: Callable[[Location], str] = str) -> str:
        """``file:line:col: error: message``, the position as ``place`` names it (for a variant, the
        ``.osc`` line the user wrote and the ``.sce`` line: see ``coverage_engine.files.sce.VariantLines``)."""
        loc = self.location
        if loc is not None and loc.is_whole_file:  # no position in it
            return f"{loc}: error: {self.message}"
        if loc is not None:
            return f"{place(loc)}: error: {self.message}"
        return f"error: {self.message}"

    def render(self) -> str:
        """The full message: ``file:line:col: error: msg``, then the source line (a window of at most
        :data:`~coverage_engine.printable.MAX_SHOWN` characters, escaped) and a caret when known."""
        lines = [self.located()]
        source_line, loc = self.source_line, self.location
        if source_line is not None and loc is not None:
            # a window of the line around the column, its control characters escaped (the caret follows)
            line, column = source_line.rstrip("\r\n").expandtabs(1), loc.column
            shown, column = clipped(line, column)
            before = printable(shown[:max(column - 1, 0)])
            lines.append("    " + before + printable(shown[max(column - 1, 0):]))
            lines.append("    " + " " * len(before) + "^")
        if self.hint:
            lines.append(f"hint: {self.hint}")
        return "\n".join(lines)


class OscError(UserError):
    """An error in a scenario, library, parameter or results file; ``str()`` says where
    (``file:line:col: error: message``)."""

    def __str__(self) -> str:
        return self.located()


class OscSyntaxError(OscError):
    """syntax error"""


class UnsupportedFeatureError(OscSyntaxError):
    """not supported"""


class ImportResolutionError(OscError):
    """cannot import"""


class ResolveError(OscError):
    """semantic error"""


class NameLookupError(ResolveError):
    """unknown name"""


class OscTypeError(ResolveError):
    """type mismatch"""


class ArgumentError(ResolveError):
    """bad argument"""


class ParameterFileError(OscError):
    """error in the scenario parameter file"""


class SceFormatError(OscError):
    """error in the .sce file"""
