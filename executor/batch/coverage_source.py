"""Runs of a batch read from the store, as the coverage merge's :class:`RunInput` records.

The store keeps each job's verdict and, when the job wrote a ``coverage.json``, its item declarations
(shared between jobs) and samples (:mod:`store.coverage_records`). Declarations are decoded and
validated once per distinct set; per job only its small JSON body is decoded. A job with no coverage
row still counts for input coverage through its verdict and its variant's assignment (the body's,
else the ``variants`` record of its scenario file). A job that ran on this host and whose folder
still holds a ``coverage.json`` the store lacks (a runner that did not record it) is read from there.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Iterator

from coverage_engine.coverage.errors import RunFileError
from coverage_engine.coverage.run_file import ItemDecl, parse_declarations, read_run_coverage
from coverage_engine.coverage.runs import RunInput, RunSource
from coverage_engine.domains import HEADER_CHARS, header_domains
from coverage_engine.results.files import COVERAGE_FILE, LOG_FILE
from coverage_engine.results.read import JunitUnreadable, read_cases
from coverage_engine.results.verdicts import VERDICT_OF_STATE, Verdict
from executor.batch.folder_history import batch_chain, latest_of
from store.coverage_records import CoverageRecords, StoredRun
from store.database import StoreError
from store.jobs import Batch
from store.queue import QueueStore
from store.states import FINAL

_decode = json.JSONDecoder().raw_decode


#: Job states (as the store writes them) that are a verdict: a later job of the same name replaces an earlier one.
_FINISHED = frozenset(state.value for state in FINAL)


def pick_batch(queue: QueueStore, results: str | None, batch_id: int | None) -> Batch:
    """The batch a report reads: ``batch_id``, else the latest whose output folder is ``results``, else the
    latest batch; :class:`StoreError` when there is none."""
    if batch_id is not None:
        return queue.batch(batch_id)
    if results is not None:
        folder = os.path.realpath(results)
        batch = queue.latest_batch(output_dir=folder)
        if batch is None:
            raise StoreError(f"the store {queue.url} holds no batch with output folder {folder} "
                             f"(give --batch ID, or leave out RESULTS for the latest batch)")
        return batch
    batch = queue.latest_batch()
    if batch is None:
        raise StoreError(f"the store {queue.url} holds no batch")
    return batch


class _StoreRuns:
    def __init__(self, records: CoverageRecords, batch_ids: list[int], source: RunSource, own: bool = True) -> None:
        #: The batch and those it continues, oldest first (see :mod:`executor.batch.folder_history`).
        self.records, self.batch_ids, self.source, self.own = records, batch_ids, source, own
        self.declarations: dict[int, tuple[tuple[ItemDecl, ...] | None, tuple[str, ...]]] = {}
        self.pending = 0
        self.from_disk = 0

    def _schema(self, schema_id: int) -> tuple[tuple[ItemDecl, ...] | None, tuple[str, ...]]:
        """The item declarations (None when they do not validate) and parameter names of a stored schema."""
        if schema_id not in self.declarations:
            text = self.records.declarations([schema_id]).get(schema_id)
            decls: tuple[ItemDecl, ...] | None = None
            parameters: tuple[str, ...] = ()
            try:
                shared = json.loads(text or "{}")
                parameters = tuple(str(p) for p in shared.get("parameters") or ())
                decls = parse_declarations(shared.get("items") or [], f"store schema {schema_id}")
            except (RunFileError, ValueError, AttributeError) as exc:
                self.source.warnings.append(f"{exc} (the jobs that use it count without their items)")
            self.declarations[schema_id] = (decls, parameters)
        return self.declarations[schema_id]

    def _run(self, row: StoredRun) -> RunInput:
        verdict = VERDICT_OF_STATE.get(row.status, Verdict.ERROR)
        if row.failed_junit:
            row = row._replace(reason=failure_message(row.failed_junit) or row.reason)
        if verdict is Verdict.PENDING:
            self.pending += 1
        folder = row.output_dir or None   # as recorded (on the host that ran it); links are not checked here
        if row.body is not None and row.schema_id is not None:
            run = self._recorded_run(row, verdict, folder, row.schema_id, row.body)
        else:
            run = self._folder_run(row, verdict, folder)
        run.scenario_file = row.scenario_path or None     # where a search reads the run's source and round
        return run

    def _recorded_run(self, row: StoredRun, verdict: str, folder: str | None, schema_id: int, body: str) -> RunInput:
        """A job whose coverage the store holds: its body decoded against the shared declarations."""
        known = self.declarations
        decls, parameters = known[schema_id] if schema_id in known else self._schema(schema_id)
        decoded = _decode(body)[0]
        values, one, samples, ignored = decoded[:4]
        unsampled = decoded[4] if len(decoded) > 4 else ()
        log = folder and f"{folder}/log.txt"
        names = parameters or None
        assignment: dict[str, object] = {}
        if names is None and row.variant_assignment:   # the run named no parameters: its variant's record
            assignment, values = self._variant(row.variant_assignment), None
        if decls is None:
            return RunInput(row.name, verdict, row.reason, folder, log, assignment, parameters=names, values=values)
        return RunInput(row.name, verdict, row.reason, folder, log, assignment, decls, samples or (),
                        ignored or (), schema_id, one, names, values, unsampled)

    def _folder_run(self, row: StoredRun, verdict: str, folder: str | None) -> RunInput:
        """A job without coverage in the store: its ``coverage.json`` when its folder is on this host."""
        run = RunInput(name=row.name, verdict=verdict, reason=row.reason, folder=folder,
                       log=os.path.join(folder, LOG_FILE) if folder else None)
        assignment: dict[str, object] = {}
        if folder is not None and verdict != Verdict.PENDING and os.path.isfile(os.path.join(folder, COVERAGE_FILE)):
            try:
                coverage = read_run_coverage(os.path.join(folder, COVERAGE_FILE))
            except RunFileError as exc:
                self.source.warnings.append(f"{exc} (its items are left out; the run still counts)")
            else:
                self.from_disk += 1
                run.items, run.samples, run.ignored = coverage.items, coverage.samples, coverage.ignored
                run.unsampled = coverage.unsampled
                assignment = dict(coverage.run.assignment)
        if not assignment and row.variant_assignment:
            assignment = self._variant(row.variant_assignment)
        run.assignment = assignment
        return run

    @staticmethod
    def _variant(text: str) -> dict[str, object]:
        """A ``variants.assignment`` JSON text as a dict ({} when it is not one)."""
        try:
            value = json.loads(text)
        except ValueError:
            return {}
        return value if isinstance(value, dict) else {}

    def _rows(self) -> Iterable[StoredRun]:
        """The jobs of the batch; for one that continues others, the latest job of each name of them all."""
        if len(self.batch_ids) == 1:
            return self.records.iter_batch(self.batch_ids[0])
        return latest_of([self.records.iter_batch(batch_id) for batch_id in self.batch_ids],
                         lambda row: row.name, lambda row: row.status in _FINISHED)

    def __iter__(self) -> Iterator[RunInput]:
        try:
            for row in self._rows():
                yield self._run(row)
        finally:
            if self.own:
                self.records.close()
        if self.pending:
            self.source.complete = False
            self.source.notes.append(f"the batch is still running: {self.pending} job(s) have not finished; "
                                     f"this report covers the finished ones")
        if self.from_disk:
            self.source.notes.append(f"{self.from_disk} job(s) had no coverage in the store; read from their "
                                     f"folders on this host")


def store_source(url: str | None, results: str | None = None, batch_id: int | None = None) -> RunSource:
    """The runs of a batch in the store at ``url``: ``batch_id``, else the latest batch whose output folder
    is ``results``, else the latest batch.

    Reading changes nothing: a store that is not there is :class:`~store.database.StoreMissing` (no file
    is created) and an older store is read as it is, never upgraded.
    """
    queue = QueueStore.open_existing(url)
    try:
        batch = pick_batch(queue, results, batch_id)
        chain = [each.id for each in reversed(batch_chain(queue, batch))]
    finally:
        queue.close()
    return batch_source(CoverageRecords.open_existing(url), batch, chain)


def batch_source(records: CoverageRecords, batch: Batch, chain: list[int] | None = None, *,
                 own: bool = True) -> RunSource:
    """The runs of ``batch`` read through ``records``: with ``chain`` (the batch and those it continues,
    oldest first) the latest job of each name of them all; ``own``: close the records once the runs are
    read (False for records on an engine the caller keeps, the batch runner's)."""
    chain = chain or [batch.id]
    label = f"batches {', '.join(map(str, chain))}" if len(chain) > 1 else f"batch {batch.id}"
    source = RunSource(label=f"{label} in {records.url}", runs=iter(()), root=batch.output_dir)
    for batch_id in chain:
        for header in records.variant_headers(batch_id, HEADER_CHARS):
            source.declare(header_domains(header))
    source.runs = iter(_StoreRuns(records, chain, source, own))
    return source


def failure_message(junit_xml: str) -> str | None:
    """The first failure's message in a job's JUnit XML: the reason the merged report gives the run (so the
    store and the results folder name the same reason); None when there is none to read."""
    try:
        cases = read_cases(junit_xml)
    except JunitUnreadable:
        return None
    return next((case.message for case in cases if case.problem and case.message), None)
