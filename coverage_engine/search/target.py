"""What an adaptive search looks for, and how finely: one value from the command line to each round.

``scenario_variation --from`` and ``scenario_search`` take the same goal options (``--objective``,
``--maximise``, ``--threshold``, ``--resolution``, ``--pass-rate``, ``--along``). They travel together:
from the command line into a variation's request or a search's settings (kept in ``search.json`` for
``--resume``), and from there into each round's :class:`~coverage_engine.search.propose.SearchOptions`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from coverage_engine.search import DEFAULT_RESOLUTION


@dataclass(frozen=True)
class SearchTarget:
    """The goal options of an adaptive strategy (their meaning: ``docs/search.md``)."""

    #: falsify: the record() item to minimise (None: the margin); boundary with ``threshold``: the item
    #: whose values cross it.
    objective: str | None = None
    maximise: bool = False
    threshold: float | None = None
    #: How finely a boundary is located, as a share of each range.
    resolution: float = DEFAULT_RESOLUTION
    #: boundary: the share of passing runs whose crossing along ``along`` (a varied parameter) is sought.
    pass_rate: float | None = None
    along: str | None = None

    def document(self) -> dict[str, Any]:
        """The options under their names, as ``search.json`` and the store's recorded options keep them."""
        return {field.name: getattr(self, field.name) for field in fields(self)}

    @classmethod
    def from_document(cls, document: Mapping[str, Any]) -> SearchTarget:
        """The options among ``document``'s entries (those absent keep their defaults)."""
        return cls(**{field.name: document[field.name] for field in fields(cls) if field.name in document})
