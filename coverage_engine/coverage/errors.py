"""Errors of the coverage tools, in the project's one exception tree (:class:`OscError`).

Each carries a location when there is one: a ``coverage.json`` value (line and column found in the
file's text), a key of the plan file, or just the file or folder. ``cli/`` renders them as
``file:line:col: error: message``.
"""

from __future__ import annotations

from coverage_engine.errors import OscError


class CoverageError(OscError):
    """coverage error"""


class RunFileError(CoverageError):
    """error in the run's coverage.json"""


class PlanError(CoverageError):
    """error in the coverage plan"""


class ResultsError(CoverageError):
    """cannot read the results"""
