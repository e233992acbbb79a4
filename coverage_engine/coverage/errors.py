"""Errors of the coverage tools, in the project's one exception tree (:class:`OscError`).

Each carries a location when there is one: a ``coverage.json`` value (line and column found in the
file's text), a key of the plan file, or just the file or folder. ``cli/`` renders them as
``file:line:col: error: message``.
"""

from __future__ import annotations

from coverage_engine.errors import OscError
from coverage_engine.location import Location


def location(file: str, line: int = 0, column: int = 0) -> Location:
    """A location in ``file``; line 0 means the file as a whole."""
    return Location(file=str(file), line=line, column=column)


class CoverageError(OscError):
    """coverage error"""


class RunFileError(CoverageError):
    """error in the run's coverage.json"""


class PlanError(CoverageError):
    """error in the coverage plan"""


class ResultsError(CoverageError):
    """cannot read the results"""
