"""Runs from a results folder: a batch's (``<job>/{test.xml,coverage.json,log.txt}`` and a merged
``test.xml``) or a single run's (``test.xml`` and ``coverage.json`` side by side).

Which runs there are, and their verdicts, come from the merged report when there is one (one
testsuite per job, with the job's ``status``, ``scenario_file`` and ``variation.*`` properties); job
folders it does not list are added from their own files, and the report is then marked incomplete
(the batch is still running, or was stopped). A run's varied parameters come from its
``coverage.json``, else from the merged report's ``variation.*`` properties, else from the ``.sce``
file the job ran (its ``assignment``).

Files are only read from inside the folder: a job folder or file that is a link leading elsewhere is
skipped and mentioned. A ``coverage.json`` that cannot be read is reported as a warning with its
location; the run still counts through its verdict.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import NamedTuple

import yaml

from coverage_engine.coverage.errors import ResultsError, RunFileError
from coverage_engine.coverage.merge import parse_assigned
from coverage_engine.coverage.run_file import RunCoverage, read_run_coverage
from coverage_engine.coverage.runs import RunInput, RunSource
from coverage_engine.coverage.search_rounds import SearchRuns
from coverage_engine.domains import (
    HEADER_CHARS,
    InputDomain,
    header_domains,
    read_declared,
)
from coverage_engine.location import Location
from coverage_engine.printable import clean_text, surrogates_escaped
from coverage_engine.results.files import COVERAGE_FILE, DECLARED_FILE, LOG_FILE, RESULT_FILE
from coverage_engine.results.read import JunitUnreadable
from coverage_engine.results.verdicts import (
    FAILING,
    VERDICT_OF_STATE,
    Verdict,
    iter_suite_verdicts,
    run_verdict,
)
from coverage_engine.search_record import SearchRecord, read_search_record, round_folder, round_folders
from coverage_engine.suffixes import SCE_SUFFIX
from coverage_engine.yaml_bounds import YamlLimitError, load_bounded

#: Largest .sce file read for its assignment.
MAX_SCE_BYTES = 16 * 1024 * 1024


def _inside(root: Path, path: Path) -> bool:
    """Whether ``path`` (links resolved) stays inside ``root``."""
    try:
        return path.resolve().is_relative_to(root)
    except OSError:
        return False


def _domains_from_sce(path: str) -> list[InputDomain]:
    """The ``# domain`` lines of a ``.sce`` file's header ([] when it cannot be read)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            return header_domains(handle.read(HEADER_CHARS))
    except OSError:
        return []


def _assignment_from_sce(path: str) -> dict[str, object]:
    """The ``assignment`` of a ``.sce`` file (YAML), or {} when it cannot be read."""
    if not path.endswith(SCE_SUFFIX):
        return {}
    try:
        if os.path.getsize(path) > MAX_SCE_BYTES:
            return {}
        with open(path, encoding="utf-8") as handle:
            doc = load_bounded(handle.read())
    except (OSError, UnicodeDecodeError, yaml.YAMLError, YamlLimitError):
        return {}
    assignment = doc.get("assignment") if isinstance(doc, dict) else None
    if not isinstance(assignment, dict):
        return {}
    return {str(k): v for k, v in assignment.items() if isinstance(v, (str, int, float, bool))}


class _Reader:
    def __init__(self, root: Path) -> None:
        self.root = root
        self.notes: list[str] = []
        self.warnings: list[str] = []
        self.skipped_links: list[str] = []
        self.missing_folders = 0
        self.orders: dict[frozenset, tuple[str, ...]] = {}
        self.declared: dict[tuple[str, frozenset], list[InputDomain]] = {}

    def declare(self, scenario_file: str, keys: Iterable[str]) -> None:
        """Note what the variation declared for ``keys`` (the ``# domain`` lines of the ``.sce`` a run ran),
        read once per folder of variants and set of parameters."""
        if not scenario_file.endswith(SCE_SUFFIX):
            return
        group = (os.path.dirname(scenario_file), frozenset(keys))
        if group not in self.declared:
            self.declared[group] = _domains_from_sce(scenario_file)

    def in_declared_order(self, assignment: dict[str, object], scenario_file: str) -> dict[str, object]:
        """The report's properties are sorted by name; the first ``.sce`` of a parameter set gives their order."""
        keys = frozenset(assignment)
        order = self.orders.get(keys)
        if order is None:
            declared = [k for k in _assignment_from_sce(scenario_file) if k in keys]
            order = self.orders[keys] = tuple(declared) if len(declared) == len(keys) else tuple(assignment)
        return {k: assignment[k] for k in order}

    def file(self, folder: Path, name: str) -> Path | None:
        path = folder / name
        if not os.path.lexists(path):
            return None
        if not _inside(self.root, path):
            self.skipped_links.append(surrogates_escaped(str(path)))
            return None
        return path if path.is_file() else None

    def coverage(self, folder: Path) -> RunCoverage | None:
        path = self.file(folder, COVERAGE_FILE)
        if path is None:
            return None
        try:
            return read_run_coverage(path)
        except RunFileError as exc:
            self.warnings.append(f"{exc} (its items are left out; the run still counts)")
            return None

    def run(self, name: str, folder: Path | None, verdict: str, reason: str | None,
            assignment: dict[str, object], coverage: RunCoverage | None,
            scenario_file: str | None = None) -> RunInput:
        log = self.file(folder, LOG_FILE) if folder is not None else None
        if coverage is not None and coverage.run.source:
            scenario_file = coverage.run.source
        if coverage is not None and coverage.run.assignment:
            assignment = dict(coverage.run.assignment)
            if coverage.run.source:
                self.declare(coverage.run.source, assignment)
        return RunInput(   # paths as text: a byte that is not UTF-8 escaped (a report cannot hold it raw)
            name=name, verdict=verdict, reason=reason,
            folder=surrogates_escaped(str(folder)) if folder is not None else None,
            log=surrogates_escaped(str(log)) if log is not None else None, assignment=assignment,
            items=coverage.items if coverage else (), samples=coverage.samples if coverage else (),
            ignored=coverage.ignored if coverage else (), unsampled=coverage.unsampled if coverage else (),
            scenario_file=scenario_file or None)


class JobFolder(NamedTuple):
    """A job's folder: its name as text (bytes that are not UTF-8 escaped, as the batch names such a job)
    and where it is."""

    name: str
    path: Path


def _job_folders(root: Path, reader: _Reader) -> dict[str, JobFolder]:
    """The job folders of ``root`` by the name the merged report gives their job (:func:`clean_text`: an
    ESC in a name is U+FFFD there), so a folder and its testsuite are one run, never two."""
    folders: dict[str, JobFolder] = {}
    for entry in sorted(os.scandir(root), key=lambda e: e.name):
        if entry.name.startswith(".") or not entry.is_dir():
            continue
        path = root / entry.name
        if entry.is_symlink() and not _inside(root, path):
            reader.skipped_links.append(surrogates_escaped(str(path)))
            continue
        if any(os.path.lexists(path / name) for name in (RESULT_FILE, COVERAGE_FILE, LOG_FILE)):
            name = surrogates_escaped(entry.name)
            folders[clean_text(name)] = JobFolder(name, path)
    return folders


def _is_merged(report: Path) -> bool:
    try:
        for suite in iter_suite_verdicts(report):
            return "status" in suite.properties and "scenario_file" in suite.properties
    except JunitUnreadable:
        return False
    return False


def _single_run(root: Path, reader: _Reader) -> Iterator[RunInput]:
    coverage = reader.coverage(root)
    report = reader.file(root, RESULT_FILE)
    verdict: str
    if report is not None:
        verdict, reason = run_verdict(report)
    elif coverage is not None:
        verdict, reason = coverage.run.verdict, coverage.run.reason
    else:
        verdict, reason = "error", "no test.xml"
    name = (coverage.run.variant if coverage and coverage.run.variant else None) or root.name
    yield reader.run(name, root, verdict, reason, {}, coverage)


def _merged_batch(root: Path, report: Path, folders: dict[str, JobFolder], reader: _Reader,
                  source: RunSource) -> Iterator[RunInput]:
    listed: set[str] = set()
    report_time = report.stat().st_mtime
    newer = 0
    try:
        for suite in iter_suite_verdicts(report):
            name = suite.name
            listed.add(clean_text(name))
            verdict = suite.verdict
            status = VERDICT_OF_STATE.get(suite.properties.get("status", ""))
            if verdict is Verdict.PASSED and status in FAILING:
                verdict = status   # the process failed although its testcases passed
            reason = None if verdict == "passed" else suite.reason or suite.properties.get("reason")
            job_folder = folders.get(name)
            folder = None if job_folder is None else job_folder.path
            if job_folder is not None:
                name = job_folder.name                 # the job's own name, as the store has it
            if folder is None:
                reader.missing_folders += "repeat.count" not in suite.properties
            elif any((folder / f).exists() and (folder / f).stat().st_mtime > report_time + 1
                     for f in (RESULT_FILE, COVERAGE_FILE)):
                newer += 1
            assignment = {k[len("variation."):]: parse_assigned(v) for k, v in suite.properties.items()
                          if k.startswith("variation.")}
            scenario_file = suite.properties.get("scenario_file", "")
            if not assignment:
                assignment = _assignment_from_sce(scenario_file)
            else:
                assignment = reader.in_declared_order(assignment, scenario_file)
            reader.declare(scenario_file, assignment)
            if "repeat.count" in suite.properties:       # a repeated variant: each attempt is a run
                attempts = repeat_attempts(suite.properties)
                listed.update(clean_text(job) for job, _, _ in attempts)
                for job, attempt_verdict, attempt_reason in attempts:
                    found = folders.get(clean_text(job))
                    where = found.path if found is not None else None
                    coverage = reader.coverage(where) if where is not None else None
                    yield reader.run(job, where, attempt_verdict, attempt_reason, assignment, coverage,
                                     scenario_file)
                continue
            coverage = reader.coverage(folder) if folder is not None else None
            yield reader.run(name, folder, verdict, reason, assignment, coverage, scenario_file)
    except JunitUnreadable as exc:
        raise ResultsError(f"the merged report cannot be read: {exc}", Location.whole_file(str(report))) from None
    extra = [name for name in folders if name not in listed]
    if extra or newer:
        source.complete = False
        if extra:
            source.notes.append(f"{len(extra)} job folder(s) are not in the merged report yet (the batch is "
                                f"still running or was stopped); they are counted from their own files")
        if newer:
            source.notes.append(f"{newer} job folder(s) changed after the merged report was written; "
                                f"their verdicts are those of the report")
    yield from _unmerged(extra, folders, reader)
    if reader.missing_folders:
        source.notes.append(f"{reader.missing_folders} job(s) of the report have no folder here (another "
                            f"host ran them): only their verdicts and parameters are counted; --store has "
                            f"their cover items")


#: How a repeated variant's attempt outcome (``repeat.attempt.<k>``) reads as a run verdict.
_ATTEMPT_VERDICTS = {state: verdict for state, verdict in VERDICT_OF_STATE.items()
                     if verdict is Verdict.PASSED or verdict in FAILING}


def repeat_attempts(properties: dict[str, str]) -> list[tuple[str, str, str | None]]:
    """``(job name, verdict, reason)`` of each attempt of a repeated variant's testsuite, from its
    ``repeat.attempt.<k>`` properties; an attempt that never ran is ``skipped``."""
    try:
        count = int(properties.get("repeat.count", "0"))
    except ValueError:
        return []
    attempts = []
    for number in range(1, count + 1):
        job = properties.get(f"repeat.attempt.{number}.job")
        if not job:
            continue
        verdict = _ATTEMPT_VERDICTS.get(properties.get(f"repeat.attempt.{number}", ""), "skipped")
        attempts.append((job, verdict, properties.get(f"repeat.attempt.{number}.reason")))
    return attempts


def _unmerged(keys: list[str], folders: dict[str, JobFolder], reader: _Reader) -> Iterator[RunInput]:
    for key in keys:
        name, folder = folders[key]
        coverage = reader.coverage(folder)
        report = reader.file(folder, RESULT_FILE)
        verdict: str
        if report is not None:
            verdict, reason = run_verdict(report)
        elif coverage is not None:
            verdict, reason = coverage.run.verdict, coverage.run.reason
        else:
            verdict, reason = "pending", "no result yet (running, or stopped before it wrote test.xml)"
        yield reader.run(name, folder, verdict, reason, {}, coverage)


def read_results_folder(path: str | os.PathLike[str]) -> RunSource:
    """The runs of a batch's results folder or of one run's output folder."""
    given = Path(path)
    if not given.exists():
        raise ResultsError("no such folder", Location.whole_file(str(given)))
    if not given.is_dir():
        raise ResultsError("not a folder (give a results folder or a run's output folder)",
                           Location.whole_file(str(given)))
    root = given.resolve()
    search = read_search_record(root)
    if search is not None:
        rounds = round_folders(root)
        if rounds:
            return _search_folder(given, search, rounds)
    reader = _Reader(root)
    source = RunSource(label=surrogates_escaped(str(given)), runs=iter(()), root=str(root))
    source.declare(read_declared(str(root / DECLARED_FILE)))     # the batch's record; .sce headers add to it
    report = reader.file(root, RESULT_FILE)
    if report is None and reader.file(root, COVERAGE_FILE) is None:
        shards = _shards(root)
        if shards:
            return read_results_folders([str(given / name) for name in shards], label=str(given))
    folders = _job_folders(root, reader)
    if report is not None and _is_merged(report):
        runs: Iterator[RunInput] = _merged_batch(root, report, folders, reader, source)
    elif report is not None or reader.file(root, COVERAGE_FILE) is not None:
        runs = _single_run(root, reader)
    elif folders:
        source.complete = False
        source.notes.append("no merged test.xml yet: the batch is still running or was stopped; the finished "
                            "job folders are counted")
        runs = _unmerged(list(folders), folders, reader)
    else:
        raise ResultsError("no results here: expected test.xml or coverage.json, or job folders holding them",
                           Location.whole_file(str(given)))

    def stream() -> Iterator[RunInput]:
        yield from runs
        if reader.skipped_links:
            source.notes.append(f"{len(reader.skipped_links)} link(s) leading out of the folder were not "
                                f"followed: {', '.join(reader.skipped_links[:3])}")
        source.warnings.extend(reader.warnings)
        for domains in reader.declared.values():
            source.declare(domains)

    source.runs = stream()
    if search is not None:
        source.search = SearchRuns(search)
        source.runs = _one_round(source.runs, source.search)
    return source


def _one_round(runs: Iterator[RunInput], collected: SearchRuns) -> Iterator[RunInput]:
    """The runs of one round's results folder (its ``search.json`` names the round), noted as that round's."""
    for run in runs:
        collected.add(run.name, run.verdict, collected.record.round, run.assignment)
        yield run


def _search_folder(given: Path, record: SearchRecord, rounds: list[tuple[int, Path]]) -> RunSource:
    """The runs of a search's folder (``scenario_search -o DIR``): every round's results folder as one
    source, each run named after its round (``round2/brake0``: the rounds name their variants alike)."""
    parts = [(number, path, read_results_folder(path)) for number, path in rounds]    # each checked first
    combined = RunSource(label=surrogates_escaped(str(given)), runs=iter(()), root=str(given.resolve()))
    collected = combined.search = SearchRuns(record)

    def stream() -> Iterator[RunInput]:
        for number, _path, part in parts:
            folder = round_folder(number)
            for run in part.runs:
                run.name = f"{folder}/{run.name}"
                collected.add(run.name, run.verdict, number, run.assignment)
                yield run
            kept = part.search.record if part.search is not None else None    # its search.json, read once
            if kept is not None and kept.strategy:
                collected.name_round(number, kept.strategy)
            combined.absorb(part, folder)
        combined.notes.insert(0, f"a search of {len(parts)} round(s): {', '.join(round_folder(n) for n, _ in rounds)}")

    combined.runs = stream()
    return combined


def _holds_jobs(folder: Path) -> bool:
    """Whether ``folder`` looks like a batch's results folder that has no merged report yet (job folders)."""
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return False
    return any(e.is_dir(follow_symlinks=False) and any(os.path.lexists(Path(e.path) / name)
                                                       for name in (RESULT_FILE, COVERAGE_FILE, LOG_FILE))
               for e in entries if not e.name.startswith("."))


def _shards(root: Path) -> list[str]:
    """The sub-folders of ``root`` that are results folders of their own: the shards of a batch, or
    batches, gathered in one folder. One with a merged ``test.xml`` makes ``root`` such a folder; a
    sub-folder holding job folders but no merged report yet (a shard stopped or still running) is one of
    them too, so the merge says it is incomplete instead of leaving it out. A sub-folder with a job's own
    ``test.xml`` (or its log) means ``root`` is a batch's folder: [] at once, without reading the rest."""
    merged, unfinished = [], []
    for entry in sorted(os.scandir(root), key=lambda e: e.name):
        if entry.name.startswith(".") or not entry.is_dir(follow_symlinks=False):
            continue
        folder = Path(entry.path)
        report = folder / RESULT_FILE
        if report.is_file() and not report.is_symlink():
            if not _is_merged(report):
                return []
            merged.append(entry.name)
        elif any(os.path.lexists(folder / name) for name in (COVERAGE_FILE, LOG_FILE)):
            return []
        elif _holds_jobs(folder):
            unfinished.append(entry.name)
    return sorted(merged + unfinished) if merged else []


def read_results_folders(paths: list[str], label: str | None = None) -> RunSource:
    """The runs of several results folders (shards of one batch, or batches) as one source: complete when
    each is, with each one's notes (prefixed by its folder) and what each variation declared."""
    unique: dict[str, str] = {}
    for path in paths:
        unique.setdefault(os.path.realpath(path), path)      # a folder named twice is read once
    paths = list(unique.values())
    if len(paths) == 1 and label is None:
        return read_results_folder(paths[0])
    sources = [read_results_folder(path) for path in paths]     # each checked before any is read
    roots = [s.root for s in sources if s.root]
    combined = RunSource(label=label or ", ".join(paths), runs=iter(()),
                         root=os.path.commonpath(roots) if roots else None)

    def stream() -> Iterator[RunInput]:
        for path, part in zip(paths, sources, strict=True):
            yield from part.runs
            combined.absorb(part, path)
        combined.notes.insert(0, f"{len(paths)} results folders merged: {', '.join(Path(p).name for p in paths)}")

    combined.runs = stream()
    return combined
