"""Variation assignments of scenario files, read from the ``variants`` table when the store has one.

The batch queue does not depend on the variation tables (another part of the store owns them): it
only asks, by file path, for the ``assignment`` JSON of files that are variants known to the store.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable

from sqlalchemy import Engine, MetaData, Table, inspect, select
from sqlalchemy.exc import SQLAlchemyError

_CHUNK = 500


def _candidates(path: str) -> set[str]:
    """Spellings under which a file may have been recorded: as given, absolute, with links resolved."""
    names = {path, os.path.abspath(path)}
    try:
        names.add(os.path.realpath(path))
    except OSError:
        pass
    return names


def variant_assignments(engine: Engine, paths: Iterable[str]) -> dict[str, dict[str, object]]:
    """Map each of ``paths`` that is a known variant to its assignment; empty when there is no ``variants`` table."""
    wanted: dict[str, str] = {}
    for path in paths:
        for name in _candidates(path):
            wanted.setdefault(name, path)
    if not wanted:
        return {}
    try:
        if not inspect(engine).has_table("variants"):
            return {}
        table = Table("variants", MetaData(), autoload_with=engine)
        if "file_path" not in table.c or "assignment" not in table.c:
            return {}
        found: dict[str, dict[str, object]] = {}
        names = sorted(wanted)
        with engine.connect() as conn:
            for start in range(0, len(names), _CHUNK):
                chunk = names[start:start + _CHUNK]
                stmt = select(table.c.file_path, table.c.assignment).where(table.c.file_path.in_(chunk))
                if "id" in table.c:
                    stmt = stmt.order_by(table.c.id)       # the newest row for a path wins
                rows = conn.execute(stmt)
                for file_path, assignment in rows:
                    value = json.loads(assignment) if isinstance(assignment, str) else assignment
                    if isinstance(value, dict):
                        found[wanted[file_path]] = value
        return found
    except (SQLAlchemyError, ValueError):
        return {}
