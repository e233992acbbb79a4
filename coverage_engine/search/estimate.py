"""What a round of search estimated: the names the adaptive strategies build and write it with.

The model of ``search.json`` (its values, writer, reader and text) is one, in
:mod:`coverage_engine.search_record`, below both the search and the coverage report in the import layers;
this module gives the strategies its values under the names they use (a round's record is a
:class:`~coverage_engine.search_record.SearchRecord` without rounds or settings).
"""

from __future__ import annotations

from pathlib import Path

from coverage_engine.search_record import (
    MAX_BOUNDARY_VARIANTS,
    AxisBoundary,
    BoundaryEstimate,
    Estimate,
    HoleCount,
    SearchRecord,
    WorstCase,
    estimate_dict,
    estimate_lines,
    round_heading,
    search_document,
    write_search_record,
)

#: A round's ``search.json``: how it was proposed, from what, and the estimate.
RoundRecord = SearchRecord

#: The JSON document of a round (what :func:`write_round` writes).
round_dict = search_document


def write_round(folder: str | Path, name: str, record: RoundRecord) -> Path:
    """Write the round's document as ``folder/name``, atomically."""
    return write_search_record(folder, record, name)


__all__ = ["MAX_BOUNDARY_VARIANTS", "AxisBoundary", "BoundaryEstimate", "Estimate", "HoleCount", "RoundRecord",
           "WorstCase", "estimate_dict", "estimate_lines", "round_dict", "round_heading", "write_round"]
