"""What ``scenario_variation`` generated: source files, variation runs and one row per variant.

Tables (SQLAlchemy Core, on the shared :data:`store.database.metadata`):

``source_files``
    one row per distinct (path, SHA-256) of an abstract ``.osc``, with its text.
``variation_runs``
    one row per ``scenario_variation`` invocation: when, the options as JSON, the source.
``variants``
    one row per concrete variant. Its identity is ``content_hash``, the SHA-256 of the ``.sce`` text
    (unique): regenerating the same input updates the same rows instead of adding new ones.
    ``file_path`` is the absolute path of the ``.sce`` as last written; when a later run replaces the
    ``.sce`` files of an output folder, rows of earlier runs there lose their ``file_path`` (NULL), so a
    lookup by path (what the batch executor does) finds exactly the variant now in that file.
    ``assignment`` is a JSON object (``"scenario.path": value``) and ``run_id`` the last run that wrote it.

Writes are executemany batches, each committed on its own (:class:`VariationRecorder`), so
100,000 rows take seconds, memory does not grow with their number, and a run stopped half way keeps
the rows of every file it wrote.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime, timezone
from itertools import islice
from typing import Any

from sqlalchemy import (
    Column,
    ColumnElement,
    Connection,
    CursorResult,
    DateTime,
    Engine,
    ForeignKey,
    Index,
    Insert,
    Integer,
    Row,
    String,
    Table,
    Text,
    UniqueConstraint,
    and_,
    bindparam,
    insert,
    select,
    update,
)
from sqlalchemy.exc import SQLAlchemyError

from store.database import StoreError, ensure_schema, metadata

source_files = Table(
    "source_files",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("path", Text, nullable=False),
    Column("sha256", String(64), nullable=False),
    Column("text", Text, nullable=False),
    UniqueConstraint("path", "sha256", name="uq_source_files_path_sha256"),
)

variation_runs = Table(
    "variation_runs",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("created_at", DateTime(timezone=True), nullable=False),
    Column("options", Text, nullable=False),
    Column("source_id", Integer, ForeignKey("source_files.id"), nullable=False),
    Column("output_dir", Text, nullable=True),
    Column("variant_count", Integer, nullable=True),
    Column("skipped_count", Integer, nullable=True),
)

variants = Table(
    "variants",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("source_id", Integer, ForeignKey("source_files.id"), nullable=False),
    Column("run_id", Integer, ForeignKey("variation_runs.id"), nullable=False),
    Column("scenario", Text, nullable=False),
    Column("idx", Integer, nullable=False),
    Column("assignment", Text, nullable=False),
    Column("sce_text", Text, nullable=False),
    Column("content_hash", String(64), nullable=False),
    Column("file_path", Text, nullable=True),
    Column("output_dir", Text, nullable=True),
    UniqueConstraint("content_hash", name="uq_variants_content_hash"),
    Index("ix_variants_file_path", "file_path"),
    Index("ix_variants_source_idx", "source_id", "idx"),
)

TABLES = [source_files, variation_runs, variants]

#: Rows per executemany batch.
BATCH_SIZE = 2000


@dataclass(frozen=True)
class VariantRecord:
    """One variant to record: its index, scenario, assignment, ``.sce`` text and where it was written.

    ``assignment`` may be given already as JSON text (as :func:`assignment_json` makes it).
    """

    index: int
    scenario: str
    assignment: Mapping[str, object] | str
    sce_text: str
    file_path: str | None = None
    content_hash: str | None = None


@dataclass(frozen=True)
class StoredVariant:
    """A row of ``variants`` as read back."""

    id: int
    source_id: int
    run_id: int
    scenario: str
    index: int
    assignment: dict[str, object]
    content_hash: str
    file_path: str | None
    sce_text: str

    @classmethod
    def from_row(cls, row: Row[Any]) -> StoredVariant:
        return cls(id=row.id, source_id=row.source_id, run_id=row.run_id, scenario=row.scenario,
                   index=row.idx, assignment=json.loads(row.assignment), content_hash=row.content_hash,
                   file_path=row.file_path, sce_text=row.sce_text)


def content_hash(sce_text: str) -> str:
    """The identity of a variant: SHA-256 (hex) of its ``.sce`` text."""
    return hashlib.sha256(sce_text.encode("utf-8")).hexdigest()


def assignment_json(assignment: Mapping[str, object]) -> str:
    """The stored form of an assignment: compact JSON, keys in generation (dimension) order."""
    return json.dumps(dict(assignment), ensure_ascii=False, separators=(", ", ": "))


def _upsert(engine: Engine, table: Table, index_elements: list[str], update_columns: list[str] | None) -> Insert | None:
    """``INSERT … ON CONFLICT`` for SQLite and PostgreSQL; None for other dialects."""
    name = engine.dialect.name
    stmt: Any
    if name == "sqlite":
        from sqlalchemy.dialects.sqlite import insert as sqlite_insert

        stmt = sqlite_insert(table)
    elif name == "postgresql":
        from sqlalchemy.dialects.postgresql import insert as postgresql_insert

        stmt = postgresql_insert(table)
    else:
        return None
    if not update_columns:
        return stmt.on_conflict_do_nothing(index_elements=index_elements)
    return stmt.on_conflict_do_update(index_elements=index_elements,
                                      set_={c: getattr(stmt.excluded, c) for c in update_columns})


def _source_id(conn: Connection, path: str, sha256: str, text: str) -> int:
    row = conn.execute(select(source_files.c.id).where(
        and_(source_files.c.path == path, source_files.c.sha256 == sha256))).first()
    if row is not None:
        return row[0]
    return _inserted_id(conn.execute(insert(source_files).values(path=path, sha256=sha256, text=text)))


def _inserted_id(result: CursorResult[Any]) -> int:
    """The primary key of the one row an ``INSERT`` wrote (SQLAlchemy types it optional: it is None only
    for an insert of several rows)."""
    key = result.inserted_primary_key
    if key is None:
        raise StoreError("the store returned no id for the row just inserted")
    return int(key[0])


def record_variation(engine: Engine, *, source_path: str, source_sha256: str, source_text: str,
                     options: Mapping[str, object], output_dir: str | None,
                     records: Iterable[VariantRecord], skipped: int = 0) -> int:
    """Record one variation run and its variants (streamed from ``records``); returns the run id.

    A :class:`VariationRecorder` fed from ``records`` in batches of :data:`BATCH_SIZE` and finished as
    a complete run.
    """
    recorder = VariationRecorder(engine, source_path=source_path, source_sha256=source_sha256,
                                 source_text=source_text, options=options, output_dir=output_dir, skipped=skipped)
    iterator = iter(records)
    while batch := list(islice(iterator, BATCH_SIZE)):
        recorder.add(batch)
    return recorder.finish(complete=True)


class VariationRecorder:
    """Records one variation run batch by batch, each batch committed on its own.

    The ``source_files`` and ``variation_runs`` rows are committed when the recorder is made, then
    every :meth:`add` commits its rows. ``scenario_variation`` commits a batch *before* writing its
    files, so a run stopped at any point (Ctrl-C, SIGTERM, a full disk) leaves a row for every
    ``.sce`` it wrote. Idempotent: a variant whose ``.sce`` text is already stored (same content hash)
    is updated (its run, file path) instead of inserted again. :meth:`finish` stores the count; for a
    complete run it also takes the ``file_path`` away from rows of earlier runs in ``output_dir``
    (their files were replaced). Raises :class:`StoreError` when the store cannot be written.
    """

    def __init__(self, engine: Engine, *, source_path: str, source_sha256: str, source_text: str,
                 options: Mapping[str, object], output_dir: str | None, skipped: int = 0) -> None:
        ensure_schema(engine, TABLES)
        self.engine, self.output_dir, self.count = engine, output_dir, 0
        with _transaction(self.engine) as conn:
            self.source_id = _source_id(conn, source_path, source_sha256, source_text)
            self.run_id = _inserted_id(conn.execute(insert(variation_runs).values(
                created_at=datetime.now(timezone.utc), options=json.dumps(dict(options), default=str),
                source_id=self.source_id, output_dir=output_dir, skipped_count=skipped,
                variant_count=0)))
            # Rows of earlier runs in this folder lose their file path batch by batch as their files are
            # overwritten, so an interrupted run leaves every path naming the variant now in the file.
            self._earlier = output_dir is not None and conn.execute(select(variants.c.id).where(and_(
                variants.c.output_dir == output_dir, variants.c.file_path.is_not(None))).limit(1)).first() is not None
        self._upsert = _upsert(engine, variants, ["content_hash"], ["run_id", "file_path", "output_dir", "idx"])

    def add(self, records: list[VariantRecord]) -> None:
        """Insert (or update) the rows of ``records`` and commit them."""
        if not records:
            return
        source_id, run_id, output_dir = self.source_id, self.run_id, self.output_dir
        batch = [{
            "source_id": source_id, "run_id": run_id, "scenario": record.scenario, "idx": record.index,
            "assignment": record.assignment if isinstance(record.assignment, str)
            else assignment_json(record.assignment),
            "sce_text": record.sce_text, "content_hash": record.content_hash or content_hash(record.sce_text),
            "file_path": record.file_path, "output_dir": output_dir,
        } for record in records]
        with _transaction(self.engine) as conn:
            if self._earlier:
                paths = [{"path": row["file_path"]} for row in batch if row["file_path"] is not None]
                if paths:
                    conn.execute(update(variants).where(and_(
                        variants.c.file_path == bindparam("path"), variants.c.run_id != run_id)).values(
                        file_path=None), paths)
            fast = (_sqlite_executemany(conn, self._upsert)
                    if self._upsert is not None and self.engine.dialect.name == "sqlite" else None)
            if fast is not None:
                fast(batch)
            elif self._upsert is not None:
                conn.execute(self._upsert, batch)
            else:  # pragma: no cover - neither SQLite nor PostgreSQL
                _portable_upsert(conn, batch)
            self.count += len(batch)
            conn.execute(update(variation_runs).where(variation_runs.c.id == run_id).values(
                variant_count=self.count))

    def finish(self, complete: bool = True) -> int:
        """Store the final count (and, for a ``complete`` run, release earlier paths); returns the run id."""
        with _transaction(self.engine) as conn:
            if complete and self.output_dir is not None:
                conn.execute(update(variants).where(and_(
                    variants.c.output_dir == self.output_dir, variants.c.run_id != self.run_id)).values(
                    file_path=None))
            conn.execute(update(variation_runs).where(variation_runs.c.id == self.run_id).values(
                variant_count=self.count))
        return self.run_id


@contextmanager
def _transaction(engine: Engine) -> Iterator[Connection]:
    """``engine.begin()`` whose database errors become :class:`StoreError`."""
    try:
        with engine.begin() as conn:
            yield conn
    except SQLAlchemyError as exc:
        raise StoreError(f"cannot record variants in {engine.url.render_as_string(hide_password=True)}: "
                         f"{exc}") from exc


_ROW_KEYS = ["source_id", "run_id", "scenario", "idx", "assignment", "sce_text", "content_hash", "file_path",
             "output_dir"]


def _sqlite_executemany(conn: Connection, upsert: Insert) -> Callable[[list[dict[str, Any]]], None] | None:
    """The upsert as one compiled SQL string run by the driver's ``executemany`` (same transaction).

    SQLAlchemy's per-row parameter processing costs more than SQLite's insert for 100,000 rows of
    plain strings and integers, and none of these columns needs a type conversion.
    """
    compiled = upsert.compile(dialect=conn.dialect, column_keys=_ROW_KEYS)
    if compiled.positiontup is None or set(compiled.positiontup) != set(_ROW_KEYS):
        return None
    order = list(compiled.positiontup)
    cursor = conn.connection.cursor()
    sql = str(compiled)

    def run(batch: list[dict[str, Any]]) -> None:
        import sqlite3

        try:
            cursor.executemany(sql, [tuple(row[key] for key in order) for row in batch])
        except sqlite3.Error as exc:  # raw driver errors bypass SQLAlchemy's wrapping
            raise StoreError(f"cannot record variants in the store: {exc}") from exc

    return run


def _portable_upsert(conn: Connection, batch: list[dict[str, Any]]) -> None:  # pragma: no cover - other dialects
    hashes = [row["content_hash"] for row in batch]
    known = set(conn.execute(select(variants.c.content_hash).where(variants.c.content_hash.in_(hashes))).scalars())
    fresh = [row for row in batch if row["content_hash"] not in known]
    if fresh:
        conn.execute(insert(variants), fresh)
    for row in batch:
        if row["content_hash"] in known:
            conn.execute(update(variants).where(variants.c.content_hash == row["content_hash"]).values(
                run_id=row["run_id"], file_path=row["file_path"], output_dir=row["output_dir"], idx=row["idx"]))


def _like_escape(text: str) -> str:
    return text.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_")


def _key_matches(wanted: str, key: str) -> bool:
    return key == wanted or key.endswith("." + wanted)


def find_variants(engine: Engine, assignment: Mapping[str, object] | None = None, *,
                  source_path: str | None = None, scenario: str | None = None,
                  current_only: bool = False, **values: object) -> list[StoredVariant]:
    """Variants whose assignment has all the given values, in (source, index) order.

    ``assignment`` keys must equal stored keys (``"test.log.msg"``); keyword arguments match a stored
    key equal to the name or ending in ``.name`` (``msg="foo"``). Values compare as JSON values. The
    database narrows the rows with ``LIKE`` on the JSON text (works on SQLite and PostgreSQL alike),
    the exact comparison happens here. ``current_only`` keeps rows that still have a file.
    """
    wanted: list[tuple[str, object, bool]] = [(k, v, True) for k, v in (assignment or {}).items()]
    wanted += [(k, v, False) for k, v in values.items()]
    ensure_schema(engine, TABLES)
    query = select(variants)
    conditions: list[ColumnElement[bool]] = []
    for key, value, exact in wanted:
        if exact:
            conditions.append(variants.c.assignment.like(
                "%" + _like_escape(json.dumps(key, ensure_ascii=False)) + ": %", escape="\\"))
        if not isinstance(value, (int, float)) or isinstance(value, bool):  # 1 and 1.0 differ as text
            conditions.append(variants.c.assignment.like(
                "%: " + _like_escape(json.dumps(value, ensure_ascii=False)) + "%", escape="\\"))
    if source_path is not None:
        query = query.join(source_files, source_files.c.id == variants.c.source_id)
        conditions.append(source_files.c.path == source_path)
    if scenario is not None:
        conditions.append(variants.c.scenario == scenario)
    if current_only:
        conditions.append(variants.c.file_path.is_not(None))
    if conditions:
        query = query.where(and_(*conditions))
    query = query.order_by(variants.c.source_id, variants.c.idx, variants.c.id)
    found = []
    try:
        with engine.connect() as conn:
            for row in conn.execute(query):
                stored = json.loads(row.assignment)
                if all(any((k == key if exact else _key_matches(key, k)) and _same_value(v, value)
                           for k, v in stored.items())
                       for key, value, exact in wanted):
                    found.append(StoredVariant.from_row(row))
    except SQLAlchemyError as exc:
        raise StoreError(f"cannot read variants: {exc}") from exc
    return found


def _same_value(stored: object, wanted: object) -> bool:
    """JSON equality: ``1 == 1.0`` but ``True != 1``; tuples compare like lists."""
    if isinstance(wanted, tuple):
        wanted = list(wanted)
    if isinstance(stored, bool) or isinstance(wanted, bool):
        return type(stored) is type(wanted) and stored == wanted
    return stored == wanted


def variant_for_file(engine: Engine, file_path: str) -> StoredVariant | None:
    """The variant now in ``file_path`` (absolute), or None (what the batch executor joins onto)."""
    ensure_schema(engine, TABLES)
    with engine.connect() as conn:
        row = conn.execute(select(variants).where(variants.c.file_path == file_path)
                           .order_by(variants.c.run_id.desc()).limit(1)).first()
    return None if row is None else StoredVariant.from_row(row)


def count_rows(engine: Engine) -> dict[str, int]:
    """Row counts of the three tables (for tests and ``--list``-style summaries)."""
    from sqlalchemy import func

    ensure_schema(engine, TABLES)
    with engine.connect() as conn:
        return {t.name: conn.execute(select(func.count()).select_from(t)).scalar_one() for t in TABLES}


__all__ = ["TABLES", "StoredVariant", "VariantRecord", "content_hash", "count_rows", "find_variants",
           "VariationRecorder", "record_variation", "source_files", "variant_for_file", "variants", "variation_runs"]
