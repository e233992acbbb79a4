"""One place that turns a store URL into a SQLAlchemy engine and guards the schema version.

Every table of the store (variation records, batch queue) is declared on :data:`metadata`,
so one ``create_all`` makes a complete store and one version row says which release made it.
"""

from __future__ import annotations

import contextlib
import os
import time
from pathlib import Path
from typing import Any

from sqlalchemy import (
    Column,
    Connection,
    Engine,
    Integer,
    MetaData,
    String,
    Table,
    create_engine,
    event,
    inspect,
    select,
    text,
)
from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError, DBAPIError, SQLAlchemyError

from coverage_engine.errors import UserError

#: Shared metadata: table modules register their tables here.
metadata = MetaData()

#: Bumped whenever a table changes in a way older code cannot read.
#: 2: per-job coverage (``coverage_schemas``, ``job_coverage`` in :mod:`store.coverage_records`).
SCHEMA_VERSION = 2

#: Older versions this release upgrades in place: since them, tables were only added (created on first use).
UPGRADABLE_FROM = frozenset({1})

#: File name of the default SQLite store, kept in the working directory (like coverage.py's ``.coverage``).
DEFAULT_STORE_FILE = ".scenario_store.db"

store_meta = Table(
    "store_meta",
    metadata,
    Column("key", String(64), primary_key=True),
    Column("value", String(255), nullable=False),
    Column("schema_version", Integer, nullable=False),
)


class StoreError(UserError):
    """The store cannot be used (bad URL, unreachable server, incompatible schema)."""


class StoreMissing(StoreError):
    """There is no store at the given place (a command that only reads never creates one): the command
    line names a store that is not there, so the command exits 2."""

    usage = True


#: SQLite's words for a write the disk or a file size limit refused.
_NO_ROOM = ("disk I/O error", "database or disk is full")


def driver_error(exc: BaseException, shown: str) -> str:
    """The message of a database error for people: a write SQLite could not make (a full disk, a
    ``ulimit -f``) names the files it was writing, where SQLite says only "disk I/O error"."""
    orig = getattr(exc, "orig", None) or exc
    text = str(orig).splitlines()[0] if str(orig) else type(orig).__name__
    path = sqlite_file(shown) if shown.startswith("sqlite") else None
    if path is not None and any(words in text for words in _NO_ROOM):
        return (f"cannot write the store {path} (or its journal {path}-wal): the disk is full or a file size "
                f"limit (ulimit -f) was reached (SQLite: {text})")
    return f"store {shown}: {text}"


def store_url(option: str | None = None) -> str:
    """The URL to use: the ``--store`` option, else ``$SCENARIO_STORE``, else the default SQLite file."""
    if option:
        return option
    env = os.environ.get("SCENARIO_STORE")
    if env:
        return env
    return "sqlite:///" + str(Path.cwd() / DEFAULT_STORE_FILE)


#: Key of the PostgreSQL advisory lock that serialises schema creation between processes.
_SCHEMA_LOCK_KEY = 0x5CE5C0DE


#: Page size of a new SQLite store (an existing file keeps the one it was created with).
PAGE_SIZE = 8192

#: How long a SQLite connection waits for another's lock before "database is locked".
BUSY_TIMEOUT_S = 30


def _sqlite_pragmas(dbapi_connection: Any, _record: object) -> None:  # pragma: no cover - trivial
    # pysqlite's own BEGIN handling is switched off; _sqlite_begin emits BEGIN IMMEDIATE instead.
    dbapi_connection.isolation_level = None
    cursor = dbapi_connection.cursor()
    # Only a new, empty file takes the page size (it must come before WAL mode is set). 8 KiB pages
    # hold three variant rows (~2 KB each with their .sce text) where 4 KiB pages held one: measured
    # on 100,000 variants, a store a third smaller written in 0.6x the time. (16 KiB gained little
    # more for variants and cost the job queue a third of its rate: every commit writes whole pages.)
    cursor.execute(f"PRAGMA page_size={PAGE_SIZE}")
    _switch_to_wal(cursor)
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.execute(f"PRAGMA busy_timeout={BUSY_TIMEOUT_S * 1000}")
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.close()


def _switch_to_wal(cursor: Any) -> None:  # pragma: no cover - trivial
    """Put the file in WAL mode, waiting out other connections that switch it at the same moment.

    On a new file several processes switching at once can meet SQLite's deadlock guard, which answers
    SQLITE_BUSY at once without calling the busy handler (6 processes opening one new store: 65 of
    1,800 connections failed so). The switch is tried again, a little later each time, for as long as
    the busy timeout would have waited.
    """
    import sqlite3  # here: only SQLite engines connect through this

    deadline = time.monotonic() + BUSY_TIMEOUT_S
    pause = 0.005
    while True:
        try:
            cursor.execute("PRAGMA journal_mode=WAL")
            return
        except sqlite3.OperationalError as exc:
            name = getattr(exc, "sqlite_errorname", None)          # (Python 3.11 on; 3.10 has the message)
            busy = name.startswith("SQLITE_BUSY") if name else str(exc).startswith("database is locked")
            if not busy or time.monotonic() + pause > deadline:
                raise
        time.sleep(pause)
        pause = min(pause * 2, 0.25)


def _sqlite_begin(dbapi_connection: Any) -> None:  # pragma: no cover - trivial
    # Take the write lock at the start of every transaction: a transaction that reads and then writes
    # would otherwise fail at once with "database is locked" when another process wrote in between
    # (WAL snapshot conflict), and the busy timeout does not help there. Sent on the driver's
    # connection as the dialect's own BEGIN (an error becomes SQLAlchemy's, as any BEGIN's would):
    # through a "begin" event and ``exec_driver_sql`` it cost a fifth of a short job's store time.
    dbapi_connection.execute("BEGIN IMMEDIATE")


def open_engine(url: str | None = None) -> Engine:
    """Create an engine for ``url`` (see :func:`store_url`); SQLite gets WAL mode and a busy timeout."""
    url = store_url(url)
    try:
        if url.startswith("sqlite"):
            engine = create_engine(url, connect_args={"timeout": BUSY_TIMEOUT_S})
            event.listen(engine, "connect", _sqlite_pragmas)
            engine.dialect.do_begin = _sqlite_begin  # type: ignore[method-assign]
        else:
            engine = create_engine(url, pool_pre_ping=True)
    except (SQLAlchemyError, ImportError, ValueError) as exc:
        raise StoreError(f"cannot open store {url!r}: {exc}") from exc
    return engine


def sqlite_file(url: str) -> str | None:
    """The database file of a SQLite URL (None for other engines, in-memory databases and bad URLs)."""
    try:
        parsed = make_url(url)
    except ArgumentError:   # reported when the URL is opened
        return None
    if not parsed.drivername.startswith("sqlite") or parsed.database in (None, "", ":memory:"):
        return None
    return parsed.database


def _check_sqlite_store(path: Path) -> None:
    """Refuse a SQLite path that holds no store, without creating or changing a file.

    Our stores are in WAL mode (header bytes 18-19 are 2): opening one with :func:`open_engine` changes
    nothing. Any other SQLite file is looked at read-only first, since opening it for writing would
    switch its journal to WAL.
    """
    if not path.is_file():
        raise StoreMissing(f"there is no store at {path.absolute()} (nothing was created)")
    try:
        with open(path, "rb") as handle:
            header = handle.read(100)
    except OSError as exc:
        raise StoreError(f"cannot read the store {path}: {exc.strerror}") from exc
    if len(header) < 20 or not header.startswith(b"SQLite format 3\x00"):
        raise StoreMissing(f"{path.absolute()} is not a scenario store (not a SQLite database)")
    if header[18] == 2 and header[19] == 2:
        return
    import sqlite3  # here: only a store that is not ours yet is looked at this way

    try:
        with contextlib.closing(sqlite3.connect(f"{path.absolute().as_uri()}?mode=ro", uri=True)) as conn:
            found = conn.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?",
                                 (store_meta.name,)).fetchone()
    except sqlite3.Error as exc:
        raise StoreError(f"cannot read the store {path}: {exc}") from exc
    if found is None:
        raise StoreMissing(f"{path.absolute()} is not a scenario store (it has no {store_meta.name} table)")


def open_existing(url: str | None = None) -> Engine:
    """An engine on a store that must exist already, for commands that only read.

    Nothing is created, upgraded or migrated: a SQLite file that is not there, or a database without the
    store's version table, raises :class:`StoreMissing`. A store of a version this release upgrades
    (:data:`UPGRADABLE_FROM`: tables were only added since) is read as it is, its version row untouched;
    the tables it lacks read as empty. Any other version raises :class:`StoreError`.
    """
    url = store_url(url)
    path = sqlite_file(url)
    if path is not None:
        _check_sqlite_store(Path(path))
    engine = open_engine(url)
    shown = engine.url.render_as_string(hide_password=True)
    try:
        with engine.connect() as conn:
            if not inspect(conn).has_table(store_meta.name):
                raise StoreMissing(f"{shown} is not a scenario store (it has no {store_meta.name} table)")
            row = conn.execute(select(store_meta.c.schema_version).where(store_meta.c.key == "schema")).first()
            check_tables(conn, shown)
    except SQLAlchemyError as exc:
        engine.dispose()
        raise StoreError(f"cannot use the store: {driver_error(exc, shown)}") from exc
    except StoreError:
        engine.dispose()
        raise
    version = None if row is None else row[0]
    if version != SCHEMA_VERSION and version not in UPGRADABLE_FROM:
        engine.dispose()
        readable = ", ".join(str(v) for v in sorted({*UPGRADABLE_FROM, SCHEMA_VERSION}))
        raise StoreError(f"the store at {shown} has schema version {version if version is not None else 'none'}, "
                         f"this release reads versions {readable}; use a matching release")
    return engine


#: What the ``value`` of the store's ``schema`` row says: this tool made the database.
STORE_MARK = "scenario-coverage"


def check_tables(conn: Connection, shown: str) -> None:
    """Refuse a database that is not a scenario store, or one whose tables lack columns, when it is opened
    (not after the first job ran): other tables and no ``store_meta`` (a foreign database, which
    ``create_all`` would otherwise fill with ours), a ``store_meta`` another tool wrote, or a table of ours
    missing a column this release writes."""
    inspector = inspect(conn)
    names = set(inspector.get_table_names())
    if store_meta.name not in names:
        foreign = sorted(names - set(metadata.tables))
        if foreign:
            raise StoreError(f"{shown} is not a scenario store: it holds other tables ({', '.join(foreign[:5])}) "
                             f"and no {store_meta.name}; give a new file or an empty database")
        return
    row = conn.execute(select(store_meta.c.value).where(store_meta.c.key == "schema")).first()
    if row is None or row[0] != STORE_MARK:
        raise StoreError(f"{shown} is not a scenario store: its {store_meta.name} table was written by "
                         f"something else; give a new file or an empty database")
    for name in sorted(names & set(metadata.tables)):
        present = {column["name"] for column in inspector.get_columns(name)}
        missing = [column.name for column in metadata.tables[name].columns if column.name not in present]
        if missing:
            raise StoreError(f"the store at {shown} is damaged: its table {name} lacks the column(s) "
                             f"{', '.join(missing)}; nothing was run (use a new store, --store)")


#: Tries of the schema check when the connection is lost during it (a database restarting, an
#: administrator ending sessions); a store that cannot be reached at all fails at once.
SCHEMA_TRIES = 4


#: SQLSTATEs of a session the server ended: admin_shutdown, crash_shutdown, cannot_connect_now.
_ENDED_STATES = frozenset({"57P01", "57P02", "57P03"})


def _session_ended(exc: SQLAlchemyError, connected: bool) -> bool:
    """Whether ``exc`` says the server ended the session (a restart, an administrator), so that a new
    connection may work: SQLAlchemy's judgement once connected; else the server's SQLSTATE, which also
    comes while connecting; or psycopg finding the session half-closed under the next statement
    ("another command is already in progress": the server ends a session asynchronously, and a test
    that ended one under the first transaction met it once on the 2-core VM)."""
    if not isinstance(exc, DBAPIError):
        return False
    if connected and exc.connection_invalidated:
        return True
    return getattr(exc.orig, "sqlstate", None) in _ENDED_STATES or "another command is already in progress" in str(exc.orig)


def ensure_schema(engine: Engine, tables: list[Table] | None = None) -> None:
    """Create missing tables (all, or just ``tables``) and refuse a store made by an incompatible version.

    Safe when several processes open a fresh store at once: everything runs in one transaction that
    holds an advisory lock on PostgreSQL and the write lock on SQLite, so "create if missing" cannot race.
    A connection lost during that transaction (it changed nothing: it is rolled back) is tried again, a
    little later, up to :data:`SCHEMA_TRIES` times: a worker started while its database drops sessions
    waits for it as it would once running.
    """
    for attempt in range(SCHEMA_TRIES):
        connected = False
        try:
            with engine.begin() as conn:
                connected = True
                _ensure_schema_in(conn, engine, tables)
            return
        except StoreError:
            raise
        except SQLAlchemyError as exc:
            if _session_ended(exc, connected) and attempt + 1 < SCHEMA_TRIES:
                time.sleep(0.1 * 2 ** attempt)
                continue
            raise StoreError(f"cannot use the store: {driver_error(exc, engine.url.render_as_string(hide_password=True))}"
                             ) from exc


def _ensure_schema_in(conn: Connection, engine: Engine, tables: list[Table] | None) -> None:
    """:func:`ensure_schema`'s transaction."""
    if conn.dialect.name == "postgresql":
        conn.execute(text("SELECT pg_advisory_xact_lock(:key)"), {"key": _SCHEMA_LOCK_KEY})
    check_tables(conn, engine.url.render_as_string(hide_password=True))
    store_meta.create(conn, checkfirst=True)
    row = conn.execute(select(store_meta.c.schema_version).where(store_meta.c.key == "schema")).first()
    if row is None:
        conn.execute(store_meta.insert().values(key="schema", value=STORE_MARK, schema_version=SCHEMA_VERSION))
    elif row[0] in UPGRADABLE_FROM:
        conn.execute(store_meta.update().where(store_meta.c.key == "schema").values(schema_version=SCHEMA_VERSION))
    elif row[0] != SCHEMA_VERSION:
        raise StoreError(
            f"the store at {engine.url.render_as_string(hide_password=True)} has schema version {row[0]}, "
            f"this release reads version {SCHEMA_VERSION}; use a new store (--store) or a matching release")
    metadata.create_all(conn, tables=tables, checkfirst=True)
