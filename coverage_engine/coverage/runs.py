"""What the merge reads per run, wherever it came from (a results folder, the store, one run folder).

A :class:`RunInput` is plain data: the run's name (the variant to rerun), its verdict, where its files
are, the values of its varied parameters, and — when the run wrote a ``coverage.json`` — its items and
samples. Runs without a ``coverage.json`` still count for input coverage through their verdict and
assignment.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from coverage_engine.coverage.run_records import ItemDecl
from coverage_engine.coverage.search_rounds import SearchRuns
from coverage_engine.domains import InputDomain
from coverage_engine.results.verdicts import Verdict

#: Verdicts of a run in a report: the run file's four, plus ``pending`` (queued or running, not finished).
REPORT_VERDICTS = tuple(verdict.value for verdict in Verdict)


@dataclass(slots=True)
class RunInput:
    """One run for the merge.

    ``schema_key`` may name the item declarations (``items``) shared by many runs, so the merge
    matches them to its items once instead of once per run (the store keeps declarations that way).
    ``single`` may replace ``samples`` when every item has exactly one sample: one value per item.
    ``parameters`` may replace ``assignment``: the parameter names (a tuple shared by many runs) and
    ``values`` their values in that order (the store keeps assignments that way).
    """

    name: str
    verdict: str
    reason: str | None = None
    folder: str | None = None
    log: str | None = None
    assignment: Mapping[str, object] = field(default_factory=dict)
    items: Sequence[ItemDecl] = ()
    samples: Sequence[list] = ()
    ignored: Sequence[int] = ()
    schema_key: Hashable | None = None
    single: Sequence | None = None
    parameters: tuple[str, ...] | None = None
    values: Sequence | None = None
    #: Per item, values of ``end`` items at a failure (see ``RunCoverage.unsampled``); usually empty.
    unsampled: Sequence[list] = ()
    #: The file the run ran (a variant's ``.sce``), when known: where its round and source are read.
    scenario_file: str | None = None


@dataclass
class RunSource:
    """A stream of runs and what is known about the set: where from, whether it is complete, notes."""

    label: str
    runs: Iterable[RunInput]  # consumed once
    complete: bool = True
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    root: str | None = None   # the local results folder, for links
    #: What the variation declared per varied parameter (the ``.sce`` headers' ``# domain`` lines), by key;
    #: filled while the runs are read.
    domains: dict[str, InputDomain] = field(default_factory=dict)
    #: The runs of a search by round (a search's folder, or one round's results), else None.
    search: SearchRuns | None = None

    def absorb(self, part: RunSource, prefix: str) -> None:
        """After ``part``'s runs were read: take in its completeness, notes (each after ``prefix``), warnings
        and declarations (one source made of several results folders)."""
        self.complete = self.complete and part.complete
        self.notes.extend(f"{prefix}: {note}" for note in part.notes)
        self.warnings.extend(part.warnings)
        self.declare(part.domains.values())

    def declare(self, domains: Iterable[InputDomain]) -> None:
        """Add the declarations of one variation (two generations of a source add up)."""
        for domain in domains:
            known = self.domains.get(domain.key)
            self.domains[domain.key] = domain if known is None else known.merged(domain)
