"""Where a variant of an adaptive search came from: its round, the strategy that proposed it, the results read.

The search loop (vary, run, read, vary again) must be visible in what it leaves behind, so that the
report can colour runs by round and a person can tell which results a proposal was made from. Every
``.sce`` written in a round carries one header comment, written once per variation like the
``# domain`` lines (:mod:`coverage_engine.domains`)::

    # proposal {"round": 2, "strategy": "boundary", "from": ["search/round1/results"]}

A variant without the line was not proposed by a search; the report counts it as round 1.

What a round estimated (the boundary located so far, the worst case found, the holes aimed at) is kept
in :data:`SEARCH_FILE` (JSON, ``{"format": SEARCH_FORMAT, ...}``) beside the round's variants and copied
with ``declared.json`` into the round's results folder.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass

#: The prefix of a proposal line in a ``.sce`` header.
PROPOSAL_PREFIX = "# proposal "

#: The file a round's estimate is kept in (beside the variants, and in the results folder of the round).
SEARCH_FILE = "search.json"

#: The ``format`` field of :data:`SEARCH_FILE`.
SEARCH_FORMAT = "scenario-coverage/search"

#: Longest proposal line written or read back (the ``from`` list is cut to fit).
MAX_PROPOSAL_LINE = 16 * 1024

#: The round of a run whose variant carries no proposal line.
FIRST_ROUND = 1


@dataclass(frozen=True)
class Proposal:
    """The round a variant belongs to, the strategy that chose it and the results folders it was chosen from."""

    round: int
    strategy: str
    sources: tuple[str, ...] = ()


def proposal_line(proposal: Proposal) -> str:
    """The header line of ``proposal`` (ending in a line break), its ``from`` list cut to fit the limit."""
    sources = list(proposal.sources)
    while True:
        body = {"round": proposal.round, "strategy": proposal.strategy, "from": sources}
        line = PROPOSAL_PREFIX + json.dumps(body, ensure_ascii=True, separators=(", ", ": ")) + "\n"
        if len(line) <= MAX_PROPOSAL_LINE or not sources:
            return line
        sources = sources[: len(sources) // 2]


def read_proposal(lines: Iterable[str]) -> Proposal | None:
    """The proposal of the first well-formed ``# proposal`` line among ``lines`` (a ``.sce`` header), else None."""
    for line in lines:
        if not line.startswith(PROPOSAL_PREFIX) or len(line) > MAX_PROPOSAL_LINE:
            continue
        try:
            body = json.loads(line[len(PROPOSAL_PREFIX):])
        except (ValueError, RecursionError):
            continue
        if not isinstance(body, dict):
            continue
        number, strategy, sources = body.get("round"), body.get("strategy"), body.get("from", [])
        if isinstance(number, int) and not isinstance(number, bool) and number >= FIRST_ROUND \
                and isinstance(strategy, str) and isinstance(sources, list) \
                and all(isinstance(s, str) for s in sources):
            return Proposal(number, strategy, tuple(sources))
    return None


def header_proposal(text: str) -> Proposal | None:
    """The proposal in the header of a ``.sce`` text (the comment lines before its first key)."""
    lines = []
    for line in text.split("\n"):
        if not line.startswith("#"):
            break
        lines.append(line)
    return read_proposal(lines)
