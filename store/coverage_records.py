"""Per-job coverage in the store: what each job's ``coverage.json`` held, so a report needs no shared disk.

Two tables (SQLAlchemy Core, on the shared :data:`store.database.metadata`):

``coverage_schemas``
    what runs of one scenario share, stored once per distinct set (keyed by SHA-256), as JSON
    ``{"parameters": [names of the assignment], "items": [item declarations without samples]}``:
    the 100,000 runs of one scenario share one row.
``job_coverage``
    one row per job (the latest attempt that wrote a file): the schema's id, the ``run`` object (JSON,
    without its assignment) and a JSON ``body`` with just what a report reads, keyless so it decodes
    fast: ``[values, one, samples, ignored]`` — the assignment's values in the schema's parameter
    order; then either ``one`` (every item has exactly one sample, the common case: one value per item)
    or ``samples`` (one list per item), the other null; and ``ignored`` (per item, the samples dropped
    at run time) or null when none were. A fifth element, ``unsampled`` (per item), follows only when a
    failing run noted the values of items whose event never came.

The batch runner calls :meth:`CoverageRecords.record` with the job's document (already read and
validated by ``coverage_engine.coverage.run_file``) when it records the job's result; reports read
back with :meth:`CoverageRecords.iter_batch`, in chunks, joined to the job's verdict and, when the
store has variation records, to the variant's assignment. The store checks nothing about coverage:
it keeps what it is given (the store imports nothing else of ours).
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Iterator, Mapping, Sequence
from typing import Any, NamedTuple

from sqlalchemy import (
    Column,
    Connection,
    Engine,
    Float,
    ForeignKey,
    Integer,
    String,
    Table,
    Text,
    case,
    delete,
    func,
    insert,
    inspect,
    null,
    select,
)
from sqlalchemy.exc import IntegrityError, SQLAlchemyError
from sqlalchemy.sql.expression import ColumnElement, FromClause

from store.database import StoreError, ensure_schema, metadata, open_engine, open_existing
from store.queue_tables import QUEUE_TABLES, jobs
from store.variants import variants

coverage_schemas = Table(
    "coverage_schemas",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("sha256", String(64), nullable=False, unique=True),
    Column("declarations", Text, nullable=False),   # JSON {"parameters": [...], "items": [declarations]}
)

job_coverage = Table(
    "job_coverage",
    metadata,
    Column("job_id", Integer, ForeignKey("jobs.id", ondelete="CASCADE"), primary_key=True),
    Column("attempt", Integer, nullable=False),
    Column("schema_id", Integer, ForeignKey("coverage_schemas.id"), nullable=False),
    Column("run", Text, nullable=False),       # JSON: the run object of the file, without "assignment"
    Column("body", Text, nullable=False),      # JSON: [values, one, samples, ignored]
    Column("recorded_at", Float, nullable=False),
)

COVERAGE_TABLES = [coverage_schemas, job_coverage]

#: Keys of an item that hold its samples rather than its declaration.
_SAMPLE_KEYS = ("samples", "ignored", "unsampled")


class StoredRun(NamedTuple):
    """A job of a batch with its verdict and, if it recorded one, its coverage (JSON texts, not decoded)."""

    seq: int
    name: str
    status: str
    reason: str | None
    output_dir: str | None
    scenario_path: str
    schema_id: int | None
    body: str | None
    variant_assignment: str | None
    #: The job's own JUnit XML when it failed (its failure message is the run's reason), else None.
    failed_junit: str | None = None


def split_document(document: Mapping[str, Any]) -> tuple[str, str, str]:
    """``(declarations, run, body)`` JSON texts of a coverage document; declarations are shared between runs."""
    items = document.get("items") or []
    run = dict(document.get("run") or {})
    assignment = run.pop("assignment", None) or {}
    shared = {"parameters": list(assignment),
              "items": [{k: v for k, v in item.items() if k not in _SAMPLE_KEYS} for item in items]}
    samples = [item.get("samples") or [] for item in items]
    one = [values[0] for values in samples] if all(len(values) == 1 for values in samples) else None
    ignored = [item.get("ignored") or 0 for item in items]
    body = [list(assignment.values()), one, None if one is not None else samples, ignored if any(ignored) else None]
    unsampled = [item.get("unsampled") or [] for item in items]
    if any(unsampled):
        body.append(unsampled)     # a failing run's values of items whose event never came (rare: kept last)
    dump = json.dumps
    return (dump(shared, sort_keys=True, separators=(",", ":"), ensure_ascii=False),
            dump(run, separators=(",", ":"), ensure_ascii=False, allow_nan=False),
            dump(body, separators=(",", ":"), ensure_ascii=False, allow_nan=False))


def join_document(shared: Mapping[str, Any], run: Mapping[str, Any], body: Sequence[Any],
                  format_name: str, format_version: int) -> dict[str, Any]:
    """The coverage document again, from its three parts (the inverse of :func:`split_document`)."""
    values, one, samples, ignored = body[:4]
    if one is not None:
        samples = [[value] for value in one]
    ignored = ignored or [0] * len(samples)
    unsampled = body[4] if len(body) > 4 else [[] for _ in samples]
    items = []
    for decl, item_samples, dropped, missed in zip(shared["items"], samples, ignored, unsampled, strict=False):
        item = dict(decl)
        if dropped:
            item["ignored"] = dropped
        item["samples"] = item_samples
        if missed:
            item["unsampled"] = missed
        items.append(item)
    assignment = dict(zip(shared["parameters"], values, strict=False))
    return {"format": format_name, "format_version": format_version, "run": {**run, "assignment": assignment},
            "items": items}


class CoverageRecords:
    """Coverage rows of jobs: :meth:`record` one, :meth:`iter_batch` read a batch's, :meth:`declarations` share."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self._schema_ids: dict[str, int] = {}

    @classmethod
    def open(cls, url: str | None = None) -> CoverageRecords:
        """Open the store at ``url`` and create the queue and coverage tables when missing."""
        engine = open_engine(url)
        ensure_schema(engine, QUEUE_TABLES + COVERAGE_TABLES)
        return cls(engine)

    @classmethod
    def open_existing(cls, url: str | None = None) -> CoverageRecords:
        """Open a store that must exist already, for reading: nothing is created or migrated.

        :class:`~store.database.StoreMissing` when there is none; a store from before per-job coverage
        (schema version 1) reads as one whose jobs recorded no coverage.
        """
        return cls(open_existing(url))

    @classmethod
    def attach(cls, engine: Engine) -> CoverageRecords:
        """Use an engine another part of the store already opened (the batch runner's), creating the tables."""
        ensure_schema(engine, QUEUE_TABLES + COVERAGE_TABLES)
        return cls(engine)

    def close(self) -> None:
        self.engine.dispose()

    @property
    def url(self) -> str:
        return self.engine.url.render_as_string(hide_password=True)

    # ------------------------------------------------------------------ writing
    def _schema_id(self, conn: Connection, declarations: str) -> int:
        digest = hashlib.sha256(declarations.encode("utf-8")).hexdigest()
        known = self._schema_ids.get(digest)
        if known is not None:
            return known
        found = conn.execute(select(coverage_schemas.c.id).where(coverage_schemas.c.sha256 == digest)).scalar()
        if found is None:
            try:
                with conn.begin_nested():
                    found = conn.execute(insert(coverage_schemas).values(sha256=digest, declarations=declarations)
                                         .returning(coverage_schemas.c.id)).scalar_one()
            except IntegrityError:   # another writer added it in between
                found = conn.execute(select(coverage_schemas.c.id)
                                     .where(coverage_schemas.c.sha256 == digest)).scalar_one()
        self._schema_ids[digest] = found
        return found

    def record(self, job_id: int, attempt: int, document: Mapping[str, Any]) -> None:
        """Keep the coverage ``document`` (a validated ``coverage.json``) of a job's ``attempt``.

        A later attempt of the same job replaces an earlier one; an earlier attempt never replaces a later.
        """
        declarations, run, body = split_document(document)
        try:
            with self.engine.begin() as conn:
                schema_id = self._schema_id(conn, declarations)
                current = conn.execute(select(job_coverage.c.attempt)
                                       .where(job_coverage.c.job_id == job_id)).scalar()
                if current is not None and current > attempt:
                    return
                conn.execute(delete(job_coverage).where(job_coverage.c.job_id == job_id))
                conn.execute(insert(job_coverage).values(job_id=job_id, attempt=attempt, schema_id=schema_id,
                                                         run=run, body=body, recorded_at=time.time()))
        except SQLAlchemyError as exc:
            self._schema_ids.clear()
            raise StoreError(f"cannot record the coverage of job {job_id} in {self.url}: {exc}") from exc

    def record_many(self, rows: Sequence[tuple[int, int, Mapping[str, Any]]]) -> None:
        """:meth:`record` for many ``(job_id, attempt, document)`` in one transaction (fresh jobs only)."""
        try:
            with self.engine.begin() as conn:
                values = []
                for job_id, attempt, document in rows:
                    declarations, run, body = split_document(document)
                    values.append(dict(job_id=job_id, attempt=attempt, schema_id=self._schema_id(conn, declarations),
                                       run=run, body=body, recorded_at=time.time()))
                if values:
                    conn.execute(delete(job_coverage).where(job_coverage.c.job_id.in_([v["job_id"] for v in values])))
                    conn.execute(insert(job_coverage), values)
        except SQLAlchemyError as exc:
            self._schema_ids.clear()
            raise StoreError(f"cannot record coverage in {self.url}: {exc}") from exc

    # ------------------------------------------------------------------ reading
    def declarations(self, schema_ids: Sequence[int]) -> dict[int, str]:
        """The declarations JSON of each schema id."""
        ids = sorted(set(schema_ids))
        out: dict[int, str] = {}
        with self.engine.connect() as conn:
            for start in range(0, len(ids), 500):
                stmt = select(coverage_schemas.c.id, coverage_schemas.c.declarations).where(
                    coverage_schemas.c.id.in_(ids[start:start + 500]))
                out.update({row[0]: row[1] for row in conn.execute(stmt)})
        return out

    def document(self, job_id: int, format_name: str, format_version: int) -> dict[str, Any] | None:
        """The job's coverage document as recorded, or None."""
        with self.engine.connect() as conn:
            row = conn.execute(select(job_coverage.c.schema_id, job_coverage.c.run, job_coverage.c.body)
                               .where(job_coverage.c.job_id == job_id)).first()
        if row is None:
            return None
        declarations = json.loads(self.declarations([row[0]])[row[0]])
        return join_document(declarations, json.loads(row[1]), json.loads(row[2]), format_name, format_version)

    def variant_headers(self, batch_id: int, chars: int) -> list[str]:
        """The start of one ``.sce`` text per variation run whose variants the batch ran (their headers
        say what each variation declared); [] for a store without variation records."""
        try:
            if not inspect(self.engine).has_table(variants.name):
                return []
            ran = select(jobs.c.scenario_path).where(jobs.c.batch_id == batch_id)
            firsts = (select(func.min(variants.c.id)).where(variants.c.file_path.in_(ran))
                      .group_by(variants.c.run_id))
            stmt = select(func.substr(variants.c.sce_text, 1, chars)).where(variants.c.id.in_(firsts))
            with self.engine.connect() as conn:
                return [row[0] for row in conn.execute(stmt) if row[0]]
        except SQLAlchemyError as exc:
            raise StoreError(f"cannot read the variants of batch {batch_id} from {self.url}: {exc}") from exc

    def iter_batch(self, batch_id: int, chunk: int = 5000) -> Iterator[StoredRun]:
        """Every job of a batch in file order, with its coverage row when there is one, read in chunks.

        A table the store does not have (no variation records; a store from before per-job coverage)
        reads as empty: reading never creates one.
        """
        try:
            tables = inspect(self.engine)
            has_variants, has_coverage = tables.has_table(variants.name), tables.has_table(job_coverage.name)
        except SQLAlchemyError as exc:
            raise StoreError(f"cannot read the coverage of batch {batch_id} from {self.url}: {exc}") from exc
        columns: list[ColumnElement[Any]] = [jobs.c.seq, jobs.c.name, jobs.c.status, jobs.c.reason,
                                             jobs.c.output_dir, jobs.c.scenario_path]
        source: FromClause = jobs
        if has_coverage:
            columns += [job_coverage.c.schema_id, job_coverage.c.body]
            source = jobs.outerjoin(job_coverage, job_coverage.c.job_id == jobs.c.id)
        else:
            columns += [null().label("schema_id"), null().label("body")]
        if has_variants:
            assignment = (select(variants.c.assignment).where(variants.c.file_path == jobs.c.scenario_path)
                          .order_by(variants.c.id.desc()).limit(1).scalar_subquery())
            columns.append(assignment.label("variant_assignment"))
        else:
            columns.append(null().label("variant_assignment"))
        columns.append(case((jobs.c.status == "failed", jobs.c.junit_xml), else_=null()).label("failed_junit"))
        last = -1
        try:
            while True:
                stmt = (select(*columns).select_from(source)
                        .where(jobs.c.batch_id == batch_id, jobs.c.seq > last).order_by(jobs.c.seq).limit(chunk))
                with self.engine.connect() as conn:
                    rows = conn.execute(stmt).all()
                yield from map(StoredRun._make, rows)
                if len(rows) < chunk:
                    return
                last = rows[-1][0]
        except SQLAlchemyError as exc:
            raise StoreError(f"cannot read the coverage of batch {batch_id} from {self.url}: {exc}") from exc
