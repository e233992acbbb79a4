"""The one exception tree of the language front end.

Every error a user can cause by what they wrote is an :class:`OscError` carrying a location when one
is known. ``cli/`` turns these into ``file:line:col: error: message`` plus the source line and a caret;
nothing below ``cli/`` prints or exits.
"""

from __future__ import annotations

from collections.abc import Callable

from coverage_engine.location import Location
from coverage_engine.printable import clipped, printable


class OscError(Exception):
    """An error in a scenario, library or parameter file."""

    def __init__(self, message: str | None = None, location: Location | None = None,
                 source_line: str | None = None, hint: str | None = None) -> None:
        self.message = message or (self.__doc__ or "error").strip().splitlines()[0]
        self.location = location
        self.source_line = source_line
        self.hint = hint
        super().__init__(self.message)

    def __str__(self) -> str:
        return self.located()

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
        lines = [str(self)]
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
