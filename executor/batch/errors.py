"""Errors of the batch runner; each class's docstring is its default message, ``cli/`` prints them."""

from __future__ import annotations


class BatchError(Exception):
    """The batch cannot be run as asked."""

    def __init__(self, message: str | None = None) -> None:
        super().__init__(message or (self.__doc__ or "").strip())


class NoScenarios(BatchError):
    """The input folder holds no .sce or .osc file."""


class BadCommand(BatchError):
    """The launch command is missing, or lacks the {SCENARIO} or {OUTPUT_DIR} placeholder."""


class BadShard(BatchError):
    """--shard must be i/N with 1 <= i <= N."""


class NothingToResume(BatchError):
    """There is no batch for this output folder to resume."""
