"""Errors of the batch runner, in the one tree of user errors; each class's docstring is its default
message, ``cli/boundary.py`` prints them."""

from __future__ import annotations

from coverage_engine.errors import UserError


class BatchError(UserError):
    """The batch cannot be run as asked."""


class NoScenarios(BatchError):
    """The input folder holds no .sce or .osc file."""


class BatchUsageError(BatchError):
    """The command line asks for something malformed (``cli/`` exits 2, as for a bad option)."""

    usage = True


class BadCommand(BatchUsageError):
    """The launch command is missing, or lacks the {SCENARIO} or {OUTPUT_DIR} placeholder."""


class CommandNotFound(BatchError):
    """The launch command's program is not found on PATH."""


class BadShard(BatchUsageError):
    """--shard must be i/N with 1 <= i <= N."""


class NothingToResume(BatchError):
    """There is no batch for this output folder to resume."""
