"""``scenario_variation --from RESULTS --store URL``: the earlier runs of a search read from the batch store.

Each ``RESULTS`` names a batch by its output folder, as ``scenario_coverage report RESULTS --store URL``
does (the latest batch written there, with the batches it continues): the folder need not be on this host.
The runs are read the way the coverage report reads a stored batch
(:func:`~executor.batch.coverage_source.batch_source`: verdicts, ``record()`` values, ``cover()`` samples,
assignments), and each run's source ``.osc`` and round come from the store's record of the variant it ran
(its source file and the ``# proposal`` line of its ``.sce`` header); a variant the store does not know is
read from its ``.sce`` file when it is on this host. The result is the same immutable
:class:`~coverage_engine.search.history.History` that results folders give, so every strategy proposes
from the store exactly as from the folders.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

from coverage_engine.coverage.runs import RunInput, RunSource
from coverage_engine.domains import HEADER_CHARS
from coverage_engine.proposals import FIRST_ROUND, header_proposal
from coverage_engine.search.history import History, OriginOf, SceOrigins, history_of
from store.variant_lookup import VariantInfo


def _origins(infos: dict[str, VariantInfo], fallback: SceOrigins) -> OriginOf:
    """Which ``.osc`` and round a run's ``.sce`` belongs to: the store's record, else the file on this host."""
    def origin_of(scenario_file: str | None) -> tuple[str | None, int]:
        info = infos.get(scenario_file) if scenario_file else None
        if info is None or not info.source:
            return fallback.of(scenario_file)
        proposal = header_proposal(info.header)
        return os.path.realpath(info.source), proposal.round if proposal is not None else FIRST_ROUND

    return origin_of


def read_stored_history(url: str | None, folders: Sequence[str], source: str | os.PathLike[str],
                        keys: Sequence[str], *, margins: bool = False) -> History:
    """The runs of ``source`` in the batches of the store at ``url`` whose output folders are ``folders``.

    :class:`~store.database.StoreMissing` when there is no store at ``url``, :class:`~store.database.StoreError`
    when it holds no batch written into one of the folders; reading changes nothing in the store.
    """
    from executor.batch.coverage_source import batch_source, pick_batch
    from executor.batch.folder_history import batch_chain
    from store.coverage_records import CoverageRecords
    from store.queue import QueueStore
    from store.variant_lookup import variant_infos

    queue = QueueStore.open_existing(url)
    try:
        batches = [pick_batch(queue, folder, None) for folder in folders]
        chains = [[each.id for each in reversed(batch_chain(queue, batch))] for batch in batches]
    finally:
        queue.close()
    records = CoverageRecords.open_existing(url)
    combined = RunSource(label=", ".join(folders), runs=iter(()))
    runs: list[RunInput] = []
    try:
        for folder, batch, chain in zip(folders, batches, chains, strict=True):
            part = batch_source(records, batch, chain, own=False)
            runs += part.runs              # read now: the store is closed below
            combined.notes.extend(f"{folder}: {note}" for note in part.notes)
            combined.declare(part.domains.values())
        files = {run.scenario_file for run in runs if run.scenario_file}
        infos = variant_infos(records.engine, files, HEADER_CHARS)
    finally:
        records.close()
    combined.runs = iter(runs)
    return history_of(combined, tuple(folders), source, keys, _origins(infos, SceOrigins([])), margins=margins)
