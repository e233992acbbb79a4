"""What the store knows about scenario files that are variants: assignment, scenario and source file.

The batch queue does not depend on the variation tables (another part of the store owns them): it
only asks, by file path, for the ``variants`` rows of files that are variants known to the store,
reading whichever of the columns it needs the table has.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from typing import Any

from sqlalchemy import Engine, Inspector, TableClause, column, func, inspect, literal, select
from sqlalchemy import table as table_clause
from sqlalchemy.exc import SQLAlchemyError

_CHUNK = 500



@dataclass(frozen=True)
class VariantInfo:
    """A variant as recorded by ``scenario_variation``: its varied values, scenario and source file."""

    assignment: dict[str, object] = field(default_factory=dict)
    scenario: str | None = None
    source: str | None = None
    #: The start of the ``.sce`` text (its header comments: how values are shown, what was declared).
    header: str = ""


def _candidates(path: str, real_folders: dict[str, str]) -> set[str]:
    """Spellings under which a file may have been recorded: as given, absolute, with links resolved.

    ``real_folders`` caches each folder's real path: the variants of a batch share a few folders, and
    resolving every file's whole path took a look at each of its parents (five system calls a job)."""
    absolute = os.path.abspath(path)
    names = {path, absolute}
    try:
        if os.path.islink(absolute) or os.pardir in path.split(os.sep):   # ".." after a link: resolve it first
            names.add(os.path.realpath(path))
        else:
            folder, name = os.path.split(absolute)
            real = real_folders.get(folder)
            if real is None:
                real = real_folders[folder] = os.path.realpath(folder)
            names.add(os.path.join(real, name))
    except OSError:
        pass
    return names


def _as_found(inspector: Inspector, name: str) -> TableClause | None:
    """The table ``name`` with the columns the store has (None when it has no such table): its column
    names only, the one thing these reads need (reflecting the whole table cost 5-10 ms a read)."""
    if not inspector.has_table(name):
        return None
    return table_clause(name, *(column(found["name"]) for found in inspector.get_columns(name)))


def _headers(conn: Any, table: TableClause, run_ids: set[int], chars: int) -> dict[int, str]:
    """The start of one ``.sce`` text per variation run (the variants of a run share their header's
    declarations), read once per run rather than once per variant."""
    if not run_ids or "run_id" not in table.c or "sce_text" not in table.c:
        return {}
    firsts = select(func.min(table.c.id)).where(table.c.run_id.in_(sorted(run_ids))).group_by(table.c.run_id)
    stmt = select(table.c.run_id, func.substr(table.c.sce_text, 1, chars)).where(table.c.id.in_(firsts))
    return {row[0]: row[1] or "" for row in conn.execute(stmt)}


def variant_infos(engine: Engine, paths: Iterable[str], header_chars: int = 0) -> dict[str, VariantInfo]:
    """Map each of ``paths`` that is a known variant to what the store says of it (empty without a ``variants`` table).

    ``header_chars`` > 0 also gives each variant the start of its variation's ``.sce`` header (one string
    shared by the variants of a variation run)."""
    wanted: dict[str, str] = {}
    real_folders: dict[str, str] = {}
    for path in paths:
        for name in _candidates(path, real_folders):
            wanted.setdefault(name, path)
    if not wanted:
        return {}
    try:
        inspector = inspect(engine)
        table = _as_found(inspector, "variants")
        if table is None or "file_path" not in table.c or "assignment" not in table.c:
            return {}
        columns: list[Any] = [table.c.file_path, table.c.assignment]
        columns.append(table.c.scenario if "scenario" in table.c else table.c.file_path.label("no_scenario"))
        run_column = table.c.run_id if "run_id" in table.c else literal(None)
        joined: Any = table
        sources = _as_found(inspector, "source_files") if "source_id" in table.c else None
        if sources is not None and "id" in sources.c and "path" in sources.c:
            joined = table.outerjoin(sources, table.c.source_id == sources.c.id)
            columns.append(sources.c.path.label("source_path"))
        found: dict[str, VariantInfo] = {}
        runs: dict[str, int] = {}
        names = sorted(wanted)
        with engine.connect() as conn:
            for start in range(0, len(names), _CHUNK):
                chunk = names[start:start + _CHUNK]
                stmt = select(*columns, run_column.label("run")).select_from(joined).where(table.c.file_path.in_(chunk))
                if "id" in table.c:
                    stmt = stmt.order_by(table.c.id)       # the newest row for a path wins
                for row in conn.execute(stmt):
                    value = json.loads(row[1]) if isinstance(row[1], str) else row[1]
                    if not isinstance(value, dict):
                        continue
                    scenario = row[2] if "scenario" in table.c else None
                    source = row[3] if len(row) > 4 else None
                    found[wanted[row[0]]] = VariantInfo(value, scenario, source)
                    if row[-1] is not None:
                        runs[wanted[row[0]]] = row[-1]
            headers = _headers(conn, table, set(runs.values()), header_chars) if header_chars > 0 else {}
        if headers:
            found = {path: replace(info, header=headers.get(runs.get(path, -1), "")) for path, info in found.items()}
        return found
    except (SQLAlchemyError, ValueError):
        return {}

