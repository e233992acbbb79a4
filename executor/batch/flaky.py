"""Flaky variants: the same variant (job name and scenario content) both passed and did not pass.

Counted over the attempts of one batch (``--repeat``) and over the batches of the same store up to
that batch, so a variant that passed last night and fails tonight with an unchanged file is called
flaky, while one whose file changed is a different variant (a regression, for ``scenario_coverage
diff``). Failed, error and timeout all count as not passing.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from executor.batch.repeats import split_attempt
from store.jobs import Job
from store.outcome_history import outcome_counts
from store.queue import QueueStore


@dataclass(frozen=True)
class VariantRecord:
    """How often a variant passed and did not pass over the batches of a store."""

    variant: str
    passed: int
    not_passed: int

    @property
    def flaky(self) -> bool:
        return self.passed > 0 and self.not_passed > 0

    def text(self) -> str:
        return f"passed {self.passed} of {self.passed + self.not_passed} run(s) in this store"


def variant_records(store: QueueStore, jobs: Iterable[Job], batch_id: int) -> dict[str, VariantRecord]:
    """Per variant of ``jobs`` (batch ``batch_id``'s, attempt suffixes taken off), its passes and
    non-passes in every batch of the store up to ``batch_id`` with the same name and content."""
    return keyed_records(store, {(job.name, job.scenario_sha) for job in jobs}, batch_id)


def keyed_records(store: QueueStore, named: set[tuple[str, str]], batch_id: int) -> dict[str, VariantRecord]:
    """:func:`variant_records` of the jobs named and contents given as ``(job name, scenario sha)``."""
    keys = {(split_attempt(name)[0], sha) for name, sha in named}
    tallies: dict[str, list[int]] = {}
    for row in outcome_counts(store.engine, batch_id):
        variant = split_attempt(row.name)[0]
        if (variant, row.sha) not in keys:
            continue
        tally = tallies.setdefault(variant, [0, 0])
        tally[0 if row.status == "passed" else 1] += row.total
    return {variant: VariantRecord(variant, passed, failed) for variant, (passed, failed) in tallies.items()}


def flaky_variants(store: QueueStore, jobs: Iterable[Job], batch_id: int) -> frozenset[str]:
    """The variants of ``jobs`` (batch ``batch_id``'s) that are flaky over the store's batches up to it."""
    return frozenset(v for v, record in variant_records(store, jobs, batch_id).items() if record.flaky)
