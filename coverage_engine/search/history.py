"""Earlier runs of one source, read back from results folders into one immutable value.

A search proposes from what was recorded, never from the scenario's code: each run's verdict, its
assignment, the values of its ``record()`` items and the samples of its ``cover()`` items, and the
round it belongs to (the ``# proposal`` line of the ``.sce`` it ran; none is round 1). The reading is
the coverage model's (:func:`~coverage_engine.coverage.results_folder.read_results_folders`), so a
search sees the same runs a report counts.

Only runs of the source being varied count: a run whose ``.sce`` names another ``.osc`` is left out
(and counted in the notes). A run whose ``.sce`` cannot be read (another host ran it, the variants
folder was moved) counts when its assignment names every axis of the variation.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from coverage_engine.coverage.results_folder import read_results_folders
from coverage_engine.coverage.run_records import ItemDecl
from coverage_engine.coverage.runs import RunInput
from coverage_engine.domains import HEADER_CHARS, InputDomain, numeric_value
from coverage_engine.proposals import FIRST_ROUND, header_proposal
from coverage_engine.results.files import RESULT_FILE
from coverage_engine.results.read import JunitUnreadable, iter_suites
from coverage_engine.results.scenario_result import CHECK_MARGIN_PROPERTY
from coverage_engine.results.verdicts import FAILING, Verdict
from coverage_engine.suffixes import SCE_SUFFIX

#: The name a run's check margin (the ``check.margin`` property of its report) is read under, as a record value.
MARGIN = "margin"

#: The verdicts of a run that finished (a pending or skipped run says nothing about its variant).
FINISHED = frozenset({Verdict.PASSED, *FAILING})


@dataclass(frozen=True)
class PastRun:
    """One earlier run: its verdict, assignment, ``record()`` values and ``cover()`` samples, and its round."""

    name: str
    verdict: str
    assignment: Mapping[str, object]
    records: Mapping[str, tuple[float, ...]] = field(default_factory=lambda: MappingProxyType({}))
    covers: Mapping[str, tuple[object, ...]] = field(default_factory=lambda: MappingProxyType({}))
    round: int = FIRST_ROUND

    @property
    def finished(self) -> bool:
        return self.verdict in FINISHED

    @property
    def failed(self) -> bool:
        """Whether the run failed (a failed check, an error or a timeout)."""
        return self.verdict in FAILING


@dataclass(frozen=True)
class History:
    """The runs read (finished or not), the folders they came from and what was noted while reading."""

    runs: tuple[PastRun, ...]
    sources: tuple[str, ...] = ()
    domains: Mapping[str, InputDomain] = field(default_factory=lambda: MappingProxyType({}))
    notes: tuple[str, ...] = ()
    #: The numeric ``cover()`` items with a range the runs declared (their holes are guessed at), by name.
    covers: Mapping[str, ItemDecl] = field(default_factory=lambda: MappingProxyType({}))

    @property
    def last_round(self) -> int:
        """The highest round among the runs (0 when there are none)."""
        return max((run.round for run in self.runs), default=0)

    @property
    def finished(self) -> tuple[PastRun, ...]:
        return tuple(run for run in self.runs if run.finished)


def _numbers(values: Iterable[object]) -> tuple[float, ...]:
    return tuple(n for n in map(numeric_value, values) if n is not None)


def _item_values(run: RunInput) -> tuple[dict[str, tuple[float, ...]], dict[str, tuple[object, ...]]]:
    """A run's ``record()`` values (numbers) and ``cover()`` samples (single items), by item name.

    An ``end`` item of a failed run was never sampled: its values at the failure (``unsampled``) stand in,
    so the record of the failing runs is not lost to a search that minimises it.
    """
    records: dict[str, tuple[float, ...]] = {}
    covers: dict[str, tuple[object, ...]] = {}
    unsampled = run.unsampled or tuple([] for _ in run.items)
    for decl, samples, missed in zip(run.items, run.samples, unsampled, strict=False):
        values = list(samples) or list(missed)
        if decl.kind == "record":
            records[decl.name] = _numbers(values)
        elif not decl.is_cross:
            covers[decl.name] = tuple(values)
    return records, covers


class _Sources:
    """What each ``.sce`` says: the ``.osc`` it came from and its round (each file read once)."""

    def __init__(self, roots: Sequence[str]) -> None:
        self.roots = roots
        self.known: dict[str, tuple[str | None, int]] = {}

    def _find(self, name: str) -> str | None:
        if os.path.isabs(name):
            return name if os.path.isfile(name) else None
        for base in (os.getcwd(), *self.roots):
            candidate = os.path.join(base, name)
            if os.path.isfile(candidate):
                return candidate
        return None

    def of(self, scenario_file: str | None) -> tuple[str | None, int]:
        """``(real path of the source .osc or None when unknown, round)`` of a run's ``.sce``."""
        if not scenario_file or not scenario_file.endswith(SCE_SUFFIX):
            return None, FIRST_ROUND
        if scenario_file not in self.known:
            self.known[scenario_file] = self._read(scenario_file)
        return self.known[scenario_file]

    def _read(self, scenario_file: str) -> tuple[str | None, int]:
        path = self._find(scenario_file)
        if path is None:
            return None, FIRST_ROUND
        from coverage_engine.errors import OscError
        from coverage_engine.files.sce import read_sce

        try:
            with open(path, encoding="utf-8", errors="replace") as handle:
                proposal = header_proposal(handle.read(HEADER_CHARS))
            document = read_sce(path)
        except (OSError, OscError):
            return None, FIRST_ROUND
        source = os.path.realpath(os.path.join(document.source_dir, document.source))
        return source, proposal.round if proposal is not None else FIRST_ROUND


def _check_margin(folder: str | None) -> float | None:
    """The check margin a run's own report holds (None without one)."""
    if folder is None:
        return None
    try:
        for suite in iter_suites(os.path.join(folder, RESULT_FILE)):
            if CHECK_MARGIN_PROPERTY in suite.properties:
                return numeric_value(float(suite.properties[CHECK_MARGIN_PROPERTY]))
    except (OSError, JunitUnreadable, ValueError):
        return None
    return None


def read_history(folders: Sequence[str], source: str | os.PathLike[str], keys: Sequence[str], *,
                 margins: bool = False) -> History:
    """The runs of ``source`` (an ``.osc``) in the results ``folders``; ``keys`` are the variation's axes.
    With ``margins``, a run's check margin (its report's ``check.margin``) is read as the record value
    ``margin``, unless the scenario records an item of that name itself.

    Raises :class:`~coverage_engine.coverage.errors.ResultsError` for a folder that holds no results.
    """
    wanted = os.path.realpath(source)
    results = read_results_folders(list(folders))
    roots = [str(Path(folder).resolve()) for folder in folders]
    sources = _Sources(roots)
    runs: list[PastRun] = []
    others = unknown = 0
    covers: dict[str, ItemDecl] = {}
    for run in results.runs:
        origin, round_number = sources.of(run.scenario_file)
        assignment = dict(run.assignment)
        if origin is not None and origin != wanted:
            others += 1
            continue
        if origin is None and not all(key in assignment for key in keys):
            unknown += 1
            continue
        records, samples = _item_values(run)
        if margins and MARGIN not in records:
            margin = _check_margin(run.folder)
            if margin is not None:
                records[MARGIN] = (margin,)
        for decl in run.items:
            if decl.kind == "cover" and decl.range is not None and not decl.is_cross:
                covers.setdefault(decl.name, decl)
        runs.append(PastRun(run.name, str(run.verdict), MappingProxyType(assignment), MappingProxyType(records),
                            MappingProxyType(samples), round_number))
    notes = list(results.notes)
    if others:
        notes.append(f"{others} run(s) of other scenario files were left out")
    if unknown:
        notes.append(f"{unknown} run(s) whose variant cannot be read and whose assignment lacks a varied "
                     "parameter were left out")
    return History(tuple(runs), tuple(folders), MappingProxyType(dict(results.domains)), tuple(notes),
                   MappingProxyType(covers))
