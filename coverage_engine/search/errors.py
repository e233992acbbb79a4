"""The errors of a search: located like every other error of ours (turned into a message by the CLI)."""

from __future__ import annotations

from coverage_engine.errors import OscError


class SearchError(OscError):
    """A search that cannot propose from these results with these options."""
