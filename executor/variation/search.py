"""``scenario_variation --from RESULTS --strategy boundary|fill-holes|falsify``: the design stage of an
adaptive round.

The earlier runs of the source are read from the results folders (:mod:`coverage_engine.search.history`),
the strategy proposes points of the unit cube over the variation's axes (:mod:`coverage_engine.search`),
and :func:`~coverage_engine.variation.design.design_points` turns them into the planned variation, so the
proposals pass the same value checks and keep conditions as any sampler's draw. Each variant carries the
``# proposal`` line (round, strategy, the folders read); the round's estimate is printed and, once the
variants are written, kept as ``OUT/search.json``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from coverage_engine.domains import InputDomain
from coverage_engine.location import Location
from coverage_engine.proposals import SEARCH_FILE, Proposal
from coverage_engine.search.errors import SearchError
from coverage_engine.search.estimate import RoundRecord, estimate_lines, round_heading, write_round
from coverage_engine.search.space import Space
from executor.variation.report import echo

if TYPE_CHECKING:
    from coverage_engine.search.history import History
    from coverage_engine.search.propose import SearchOptions
    from coverage_engine.variation.plan import ParsedVariation, PlannedVariation


@dataclass(frozen=True)
class AdaptiveRound:
    """The planned variants of one adaptive round and the record of what it estimated."""

    planned: PlannedVariation
    record: RoundRecord


def space_of(parsed: ParsedVariation) -> Space:
    """The axes of the variation as the unit cube the search works in (the mapping ``design_points`` applies)."""
    from coverage_engine.variation.plan import DOCUMENT_KEY

    axes = []
    for dim in parsed.dimensions:
        spec = dim.continuous
        if spec is not None:
            axes.append(InputDomain(dim.key, low=spec.low, high=spec.high, unit=spec.unit))
        else:
            axes.append(InputDomain(dim.key, values=tuple(choice.stored for choice in dim.choices)))
    if parsed.documents is not None:
        axes.append(InputDomain(DOCUMENT_KEY, values=tuple(range(len(parsed.documents)))))
    return Space(tuple(axes))


def adaptive_round(parsed: ParsedVariation, options: SearchOptions,
                   results_store: str | None = None) -> AdaptiveRound:
    """Read the earlier runs (from the folders, or with ``results_store`` from the batches of that store written
    into them), propose this round's points and plan them as variants; the estimate is printed."""
    from coverage_engine.search.propose import propose_round
    from coverage_engine.variation.design import design_points

    strategy = options.strategy
    if not parsed.sizes:
        raise SearchError(f"--strategy {strategy} searches over the varied parameters, and {parsed.path.name} "
                          "varies none", Location.whole_file(str(parsed.path)))
    space = space_of(parsed)
    proposal = propose_round(space, _history(parsed, space, options, results_store), options)
    for note in proposal.notes:
        echo(f"note: {note}")
    record = proposal.record
    echo(round_heading(record))
    for line in estimate_lines(record.estimate):
        echo(line)
    columns = [list(column) for column in zip(*proposal.points, strict=True)] if proposal.points \
        else [[] for _ in space.axes]
    note = f"strategy {strategy}, round {record.round}, {options.samples} samples, seed {options.seed}"
    planned = design_points(parsed, columns, note=note, samples=options.samples,
                            proposal=Proposal(record.round, strategy, options.sources))
    return AdaptiveRound(planned, record)


def estimate_only(scenario: Path, options: SearchOptions) -> RoundRecord:
    """What ``options.strategy`` estimates from the runs of ``options.sources`` (results folders of
    ``scenario``'s variants), proposing nothing and printing nothing: the search's estimate after its last
    round."""
    from coverage_engine.search.propose import estimate_round
    from coverage_engine.variation.plan import parse_variation

    parsed = parse_variation(scenario)
    space = space_of(parsed)
    return estimate_round(space, _history(parsed, space, options, None), options)


def _history(parsed: ParsedVariation, space: Space, options: SearchOptions, results_store: str | None) -> History:
    """The earlier runs of ``parsed``'s source in ``options.sources``: results folders, or with
    ``results_store`` the batches of that store written into them (the margins read only for falsify on it)."""
    from coverage_engine.search.history import MARGIN, read_history

    margins = options.strategy == "falsify" and options.target.objective in (None, MARGIN)
    if results_store is not None:
        from executor.variation.stored_results import read_stored_history

        return read_stored_history(results_store, options.sources, parsed.path, space.keys, margins=margins)
    return read_history(options.sources, parsed.path, space.keys, margins=margins)


def write_estimate(output_dir: str, record: RoundRecord) -> Path:
    """Keep the round's estimate beside its variants (``OUT/search.json``, written atomically)."""
    return write_round(output_dir, SEARCH_FILE, record)
