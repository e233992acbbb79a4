"""The rounds of a search in the coverage report: which runs each round ran, and what the search estimated.

A search's folder (``scenario_search -o DIR``) holds one results folder per round; the reader
(:mod:`coverage_engine.coverage.results_folder`) reads them all as one source and hands each run to a
:class:`SearchRuns` with its round, as a round's own results folder does with the round its
``search.json`` names. At the end :meth:`SearchRuns.section` makes the report's :class:`SearchSection`:
the runs and failures per round, the estimate of the latest round (the boundary, the worst case, the
holes aimed at), and, for the HTML scatter, each run's round, verdict and values of two drawn ranges.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from coverage_engine.domains import InputDomain
from coverage_engine.results.verdicts import FAILING
from coverage_engine.search_record import Estimate, SearchRecord

#: Most runs the search's scatter shows (the report's other scatters have the same bound).
MAX_SEARCH_POINTS = 5_000


@dataclass(frozen=True)
class RoundCount:
    """One round in the report: its strategy, its runs, and how many passed and did not."""

    round: int
    strategy: str
    runs: int
    passed: int
    not_passed: int


@dataclass(frozen=True)
class SearchPoint:
    """One run on the search's scatter: its values of the two ranges, its round, verdict and name."""

    x: float
    y: float
    round: int
    verdict: str
    name: str


@dataclass(frozen=True)
class SearchSection:
    """What the report says of a search: the goal, the rounds, the latest estimate, the runs by round."""

    goal: str | None
    budget: int | None
    latest_round: int
    estimate: Estimate
    rounds: tuple[RoundCount, ...]
    #: Each run's round, by run name (the JSON lists them; the scatter colours by them).
    run_rounds: tuple[tuple[str, int], ...] = ()
    #: The two drawn ranges of the scatter: ``(key, low, high, unit)`` each; empty when there are fewer.
    axes: tuple[tuple[str, float, float, str], ...] = ()
    points: tuple[SearchPoint, ...] = ()


@dataclass
class _Round:
    strategy: str = ""
    runs: int = 0
    passed: int = 0
    not_passed: int = 0


@dataclass
class SearchRuns:
    """Collects the runs of a search as they are read: their rounds, verdicts and assignments."""

    record: SearchRecord
    rounds: dict[int, _Round] = field(default_factory=dict)
    names: list[str] = field(default_factory=list)
    numbers: list[int] = field(default_factory=list)
    verdicts: list[str] = field(default_factory=list)
    assignments: list[Mapping[str, object]] = field(default_factory=list)

    def add(self, name: str, verdict: str, round_number: int, assignment: Mapping[str, object]) -> None:
        """One run of round ``round_number``."""
        counted = self.rounds.setdefault(round_number, _Round())
        counted.runs += 1
        if verdict == "passed":
            counted.passed += 1
        elif verdict in FAILING:
            counted.not_passed += 1
        self.names.append(name)
        self.numbers.append(round_number)
        self.verdicts.append(verdict)
        self.assignments.append(assignment)

    def name_round(self, round_number: int, strategy: str) -> None:
        """The strategy of a round (from its own ``search.json``) when the search's file does not name it."""
        self.rounds.setdefault(round_number, _Round()).strategy = strategy

    def section(self, domains: Mapping[str, InputDomain]) -> SearchSection:
        """The report's section, ``domains`` being what the variations declared (the scatter's ranges)."""
        named = {r.round: r.strategy for r in self.record.rounds}
        rounds = tuple(RoundCount(number, named.get(number) or counted.strategy
                                  or (self.record.strategy if number == self.record.round else ""),
                                  counted.runs, counted.passed, counted.not_passed)
                       for number, counted in sorted(self.rounds.items()))
        ranges = [d for d in domains.values() if d.drawn and d.low is not None and d.high is not None][:2]
        axes = tuple((d.key, float(d.low or 0), float(d.high or 0), d.unit) for d in ranges)
        settings = self.record.settings
        goal, budget = settings.get("goal"), settings.get("budget")
        return SearchSection(
            goal=goal if isinstance(goal, str) else None, budget=budget if isinstance(budget, int) else None,
            latest_round=max((r.round for r in rounds), default=self.record.round),
            estimate=self.record.estimate, rounds=rounds,
            run_rounds=tuple(zip(self.names, self.numbers, strict=True)),
            axes=axes if len(axes) == 2 else (), points=self._points(axes) if len(axes) == 2 else ())

    def _points(self, axes: tuple[tuple[str, float, float, str], ...]) -> tuple[SearchPoint, ...]:
        (x_key, *_), (y_key, *_) = axes
        points = []
        for name, number, verdict, assignment in zip(self.names, self.numbers, self.verdicts, self.assignments,
                                                      strict=True):
            x, y = assignment.get(x_key), assignment.get(y_key)
            if isinstance(x, (int, float)) and isinstance(y, (int, float)) \
                    and not isinstance(x, bool) and not isinstance(y, bool):
                points.append(SearchPoint(float(x), float(y), number, verdict, name))
        if len(points) > MAX_SEARCH_POINTS:                # the latest rounds first: they show the estimate
            points.sort(key=lambda p: -p.round)
            points = points[:MAX_SEARCH_POINTS]
        return tuple(points)
