"""Errors of the batch runner; each class's docstring is its default message, ``cli/`` prints them."""

from __future__ import annotations


class BatchError(Exception):
    """The batch cannot be run as asked."""

    def __init__(self, message: str | None = None) -> None:
        super().__init__(message or (self.__doc__ or "").strip())


class NoScenarios(BatchError):
    """The input folder holds no .sce or .osc file."""


class BatchUsageError(BatchError):
    """The command line asks for something malformed (``cli/`` exits 2, as for a bad option)."""


class BadCommand(BatchUsageError):
    """The launch command is missing, or lacks the {SCENARIO} or {OUTPUT_DIR} placeholder."""


class CommandNotFound(BatchError):
    """The launch command's program is not found on PATH."""


class BadShard(BatchUsageError):
    """--shard must be i/N with 1 <= i <= N."""


class NothingToResume(BatchError):
    """There is no batch for this output folder to resume."""
