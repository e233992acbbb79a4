"""One place that turns a store URL into a SQLAlchemy engine and guards the schema version.

Every table of the store (variation records, batch queue) is declared on :data:`metadata`,
so one ``create_all`` makes a complete store and one version row says which release made it.
"""

from __future__ import annotations

import os
from pathlib import Path

from sqlalchemy import Column, Engine, Integer, MetaData, String, Table, create_engine, event, select
from sqlalchemy.exc import SQLAlchemyError

#: Shared metadata: table modules register their tables here.
metadata = MetaData()

#: Bumped whenever a table changes in a way older code cannot read.
SCHEMA_VERSION = 1

#: File name of the default SQLite store, kept in the working directory (like coverage.py's ``.coverage``).
DEFAULT_STORE_FILE = ".scenario_store.db"

store_meta = Table(
    "store_meta",
    metadata,
    Column("key", String(64), primary_key=True),
    Column("value", String(255), nullable=False),
    Column("schema_version", Integer, nullable=False),
)


class StoreError(Exception):
    """The store cannot be used (bad URL, unreachable server, incompatible schema)."""


def store_url(option: str | None = None) -> str:
    """The URL to use: the ``--store`` option, else ``$SCENARIO_STORE``, else the default SQLite file."""
    if option:
        return option
    env = os.environ.get("SCENARIO_STORE")
    if env:
        return env
    return "sqlite:///" + str(Path.cwd() / DEFAULT_STORE_FILE)


def _sqlite_pragmas(dbapi_connection, _record) -> None:  # pragma: no cover - trivial
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.execute("PRAGMA busy_timeout=30000")
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.close()


def open_engine(url: str | None = None) -> Engine:
    """Create an engine for ``url`` (see :func:`store_url`); SQLite gets WAL mode and a busy timeout."""
    url = store_url(url)
    try:
        if url.startswith("sqlite"):
            engine = create_engine(url, connect_args={"timeout": 30})
            event.listen(engine, "connect", _sqlite_pragmas)
        else:
            engine = create_engine(url, pool_pre_ping=True)
    except (SQLAlchemyError, ImportError, ValueError) as exc:
        raise StoreError(f"cannot open store {url!r}: {exc}") from exc
    return engine


def ensure_schema(engine: Engine, tables: list[Table] | None = None) -> None:
    """Create missing tables (all, or just ``tables``) and refuse a store made by an incompatible version."""
    try:
        store_meta.create(engine, checkfirst=True)
        with engine.begin() as conn:
            row = conn.execute(select(store_meta.c.schema_version).where(store_meta.c.key == "schema")).first()
            if row is None:
                conn.execute(store_meta.insert().values(key="schema", value="scenario-coverage",
                                                        schema_version=SCHEMA_VERSION))
            elif row[0] != SCHEMA_VERSION:
                raise StoreError(
                    f"the store at {engine.url.render_as_string(hide_password=True)} has schema version {row[0]}, "
                    f"this release reads version {SCHEMA_VERSION}; use a new store (--store) or a matching release")
        metadata.create_all(engine, tables=tables, checkfirst=True)
    except StoreError:
        raise
    except SQLAlchemyError as exc:
        raise StoreError(f"cannot use store {engine.url.render_as_string(hide_password=True)}: {exc}") from exc
