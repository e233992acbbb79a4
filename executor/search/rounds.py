"""One round of a search: write its variants (the variation, in-process), then run them (a batch, in-process).

Round 1 samples the ranges plainly (a Latin hypercube of ``--round`` variants; every combination when
nothing is continuous and the product fits in a round); every later round asks the goal's strategy
for the next variants from the results of all earlier rounds. The variation and the batch are the
ones ``scenario_variation`` and ``scenario_batch_execution`` run — the same checks, store records,
folder locks and reports — called as functions, not launched. Their chatter (a line per written file)
is kept out of the search's output unless ``-d`` is given; their warnings and errors are not.
"""

from __future__ import annotations

import contextlib
import io
import os
from dataclasses import dataclass, replace
from pathlib import Path

from coverage_engine.results.files import RESULT_FILE
from coverage_engine.search_record import (
    RESULTS_FOLDER,
    VARIANTS_FOLDER,
    RoundSummary,
    SearchRecord,
    round_folder,
)
from coverage_engine.suffixes import SCE_SUFFIX
from executor.batch import orchestration
from executor.batch.errors import BatchError
from executor.batch.progress import Reporter
from executor.output.terminal import printable
from executor.search.request import SearchRequest
from executor.variation.request import VariationRequest
from executor.variation.writing import EXIT_INTERRUPTED
from store.jobs import Batch, BatchOptions
from store.queue import QueueStore
from store.states import JobState

#: Seconds between looks at the store while the workers run a round (``--enqueue-only``).
WAIT_POLL = 0.25

#: The sampler of round 1 when a range is continuous or the product of the values does not fit a round.
FIRST_SAMPLER = "lhs"


def say(text: str) -> None:
    """One line for people on stdout, flushed so it interleaves with the warnings on stderr."""
    print(printable(text), flush=True)


class SearchInterrupted(Exception):
    """Ctrl-C (or SIGTERM) stopped a round; ``--resume`` continues it."""


@dataclass(frozen=True)
class RoundPlace:
    """Where round ``number`` of a search keeps its variants and its results."""

    number: int
    variants: Path
    results: Path

    @classmethod
    def of(cls, folder: str, number: int) -> RoundPlace:
        base = Path(folder) / round_folder(number)
        return cls(number, base / VARIANTS_FOLDER, base / RESULTS_FOLDER)


@dataclass(frozen=True)
class RoundRun:
    """How a round's batch ended: its variants, how many did not pass, and the signal that stopped it."""

    runs: int
    failed: int
    signum: int | None


def first_strategy(scenario: str, samples: int) -> str:
    """``full`` when no range is continuous and every combination fits in ``samples``, else the sampler."""
    import math

    from coverage_engine.variation.plan import parse_variation

    parsed = parse_variation(Path(scenario))
    if any(dimension.continuous is not None for dimension in parsed.dimensions):
        return FIRST_SAMPLER
    return "full" if math.prod(parsed.sizes) <= samples else FIRST_SAMPLER


def variation_request(request: SearchRequest, place: RoundPlace, strategy: str, samples: int,
                      sources: tuple[Path, ...]) -> VariationRequest:
    """The variation of one round: round 1 a plain sampler, later rounds the goal's strategy reading
    ``sources`` (the results folders of every earlier round)."""
    settings = request.settings
    seed = settings.seed + place.number - 1        # each round its own draw, the same again on --resume
    variation = VariationRequest(scenario=settings.scenario, output_dir=str(place.variants), store=request.store,
                                 strategy=strategy, samples=None if strategy == "full" else samples, seed=seed,
                                 debug=request.debug, round_number=place.number)
    if not sources:
        return variation
    return replace(variation, from_results=tuple(str(s) for s in sources), target=settings.target)


def final_estimate(request: SearchRequest, folder: Path, done: tuple[RoundSummary, ...]) -> SearchRecord:
    """The goal's estimate from the results of every round in ``done`` (the last one included), proposing
    nothing; it is kept as the estimate of the last round."""
    from coverage_engine.search.propose import SearchOptions
    from executor.variation.search import estimate_only

    settings = request.settings
    last = done[-1].round
    sources = tuple(str(RoundPlace.of(str(folder), r.round).results) for r in done)
    options = SearchOptions(settings.goal, settings.round_size, settings.seed + last, sources, settings.target,
                            round_number=last)
    return estimate_only(Path(settings.scenario), options)


def write_variants(variation: VariationRequest, *, show: bool) -> int:
    """Write the round's variants; returns how many ``.sce`` files the folder holds. The variation's own
    lines are shown only when ``show`` (``-d``); when it wrote none they are said with the error."""
    from executor.variation.generation import run

    place = Path(variation.output_dir)
    place.mkdir(parents=True, exist_ok=True)
    quiet = io.StringIO()
    with contextlib.nullcontext() if show else contextlib.redirect_stdout(quiet):
        code = run(variation)
    if code == EXIT_INTERRUPTED:
        raise SearchInterrupted(f"stopped while writing the variants of {place}")
    written = sum(1 for name in os.listdir(place) if name.endswith(SCE_SUFFIX))
    said = quiet.getvalue().strip()
    if not written and not _goal_met(place):
        raise BatchError(f"the variation wrote no variant into {place}: nothing to run" + (f"\n{said}" if said else ""))
    return written


def _goal_met(variants: Path) -> bool:
    """Whether the round's estimate (its ``search.json``) says the goal is met."""
    from coverage_engine.search_record import read_search_record

    record = read_search_record(variants)
    return record is not None and record.estimate.done


def open_batch(store: QueueStore, request: SearchRequest, place: RoundPlace) -> Batch:
    """The batch of the round's variants (a new one), run as the search's settings say."""
    settings = request.settings
    batch_request = orchestration.BatchRequest(
        input_dir=str(place.variants), output_dir=orchestration.output_folder(str(place.results)),
        command=settings.command,
        options=BatchOptions(timeout=settings.timeout, retries=settings.retries, grace=settings.grace,
                             simulation=settings.simulation))
    return orchestration.create_batch(store, batch_request, mode="shared" if request.enqueue_only else "local")


def round_batch(store: QueueStore, place: RoundPlace) -> Batch | None:
    """The batch already made for the round's results folder (a resumed round), else None."""
    if not place.results.is_dir():
        return None
    return store.latest_batch(output_dir=orchestration.output_folder(str(place.results)))


def run_batch(store: QueueStore, batch: Batch, request: SearchRequest, reporter: Reporter) -> RoundRun:
    """Run the batch's remaining jobs (``-j`` in parallel; with ``--enqueue-only`` the workers run them and
    this waits) and write its report; count its variants."""
    store.resume(batch.id)              # jobs a Ctrl-C cancelled are queued again
    if request.enqueue_only:
        return _wait_for_workers(store, batch)
    ran = orchestration.run_local(store, batch, request.slots, reporter, lease=request.lease, echo_children=False)
    counts = ran.counts
    if ran.disk_full is not None:
        raise BatchError(f"no space left on the device holding {ran.disk_full}: the search stopped; make room, "
                         "then run it again with --resume")
    failed = sum(n for state, n in counts.items() if state is not JobState.PASSED)
    return RoundRun(sum(counts.values()), failed, ran.signum)


def _unfinished(store: QueueStore, batch: Batch) -> int:
    counts = store.counts(batch.id)
    return counts[JobState.QUEUED] + counts[JobState.RUNNING]


def _wait_for_workers(store: QueueStore, batch: Batch) -> RoundRun:
    """``--enqueue-only``: wait until the workers sharing the store have run every job of the round's batch
    (Ctrl-C stops the wait, not the workers: ``--resume`` waits again), then write the round's report."""
    import time

    left = _unfinished(store, batch)
    if left:
        say(f"round batch {batch.id}: {left} job(s) queued in the shared store; waiting for "
                     "'scenario_batch_execution worker --store URL' to run them")
    while left:
        time.sleep(WAIT_POLL)
        left = _unfinished(store, batch)
    outcome = orchestration.write_outcome_report(store, batch, Path(batch.output_dir) / RESULT_FILE)
    failed = sum(n for state, n in outcome.counts.items() if state is not JobState.PASSED)
    return RoundRun(sum(outcome.counts.values()), failed, None)
