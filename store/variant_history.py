"""What earlier variation runs of one source left in one folder: for ``scenario_variation --only-new``.

An incremental run writes only the variants whose assignment is not held yet (same source path and
text, same output folder, file still recorded there), numbers them after the highest index held, and
continues the earlier runs' draw or covering array (their options say how).
"""

from __future__ import annotations

import json
from dataclasses import dataclass

from sqlalchemy import Engine, and_, func, select

from store.variants import source_files, variants, variation_runs


@dataclass(frozen=True)
class HeldVariants:
    """The assignments (as stored JSON text) held for a source in a folder, the next free index, and the
    options of the earlier runs (oldest first)."""

    assignments: frozenset[str]
    next_index: int
    runs: tuple[dict, ...]


def held_variants(engine: Engine, *, source_path: str, source_sha256: str, output_dir: str) -> HeldVariants:
    """The variants earlier runs of this source (path and text) wrote into ``output_dir`` and that are still
    recorded there; an empty record when the store holds none (or has no variation tables yet)."""
    from sqlalchemy import inspect

    if not inspect(engine).has_table(variants.name):
        return HeldVariants(frozenset(), 0, ())
    same_source = and_(source_files.c.path == source_path, source_files.c.sha256 == source_sha256)
    with engine.connect() as conn:
        rows = conn.execute(
            select(variants.c.assignment, variants.c.idx)
            .select_from(variants.join(source_files, variants.c.source_id == source_files.c.id))
            .where(same_source, variants.c.output_dir == output_dir, variants.c.file_path.is_not(None))).all()
        # the highest index any run of this source used in this folder, recorded or not: never reused
        top = conn.execute(
            select(func.max(variants.c.idx))
            .select_from(variants.join(source_files, variants.c.source_id == source_files.c.id))
            .where(source_files.c.path == source_path, variants.c.output_dir == output_dir)).scalar()
        runs = conn.execute(
            select(variation_runs.c.options)
            .select_from(variation_runs.join(source_files, variation_runs.c.source_id == source_files.c.id))
            .where(same_source, variation_runs.c.output_dir == output_dir)
            .order_by(variation_runs.c.id)).scalars().all()
    options = []
    for text in runs:
        try:
            value = json.loads(text)
        except ValueError:
            continue
        if isinstance(value, dict):
            options.append(value)
    return HeldVariants(frozenset(a for a, _ in rows), 0 if top is None else int(top) + 1, tuple(options))
