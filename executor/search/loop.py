"""The rounds of a search one after another, until ``--budget`` runs or the goal is met.

State lives on disk, so Ctrl-C loses nothing and ``--resume`` continues where the search stopped:
the search's ``search.json`` (its settings, written before round 1, and each finished round, written
after it) and the store (each round's batch). A round that was stopped is continued: its batch
resumed when it has one (every run recorded once, as ``scenario_batch_execution --resume`` does),
its variants written again (the same seed, so the same variants) when it stopped before its batch.

Output, in a pipe as on a terminal: one line per round (the round, its runs and failures, the runs
so far against the budget, the estimate its variants were proposed from), then the estimate in a few
lines. Each round's estimate is made while proposing, before the round runs; so once the last round ran,
the goal's strategy estimates once more from every round (proposing nothing), and that is what the last
words and the search's ``search.json`` say.
"""

from __future__ import annotations

import signal
import sys
from dataclasses import replace
from pathlib import Path

from coverage_engine.proposals import SEARCH_FILE
from coverage_engine.search_record import (
    Estimate,
    RoundSummary,
    SearchRecord,
    estimate_lines,
    estimate_summary,
    read_search_record,
    write_search_record,
)
from executor.batch.errors import BatchError, NothingToResume
from executor.batch.orchestration import EXIT_INTERRUPTED
from executor.batch.progress import Reporter
from executor.output.terminal import printable
from executor.search import rounds
from executor.search.request import SearchRequest, SearchSettings, resumed
from store.queue import QueueStore

#: Exit code of a search that ran to its end (the budget spent or the goal met), failures found or not:
#: finding them is what it is for.
EXIT_DONE = 0

#: Exit code of a search that Ctrl-C stopped (SIGTERM: 143).
EXIT_STOPPED = EXIT_INTERRUPTED[signal.SIGINT]


say = rounds.say


class _QuietReporter(Reporter):
    """The search's batches print no line per job (the round's line says how they went); warnings do."""

    def warn(self, text: str) -> None:
        print(f"warning: {printable(text)}", file=sys.stderr, flush=True)


def _save(folder: Path, record: SearchRecord) -> None:
    write_search_record(folder, record)


def _start(request: SearchRequest, folder: Path) -> tuple[SearchRequest, SearchRecord]:
    """The search's record: a new one, or (``--resume``) the one in ``folder`` with its settings."""
    kept = read_search_record(folder)
    if request.resume:
        settings = SearchSettings.from_document(kept.settings) if kept is not None else None
        if kept is None or settings is None:
            raise NothingToResume(f"there is no search in {folder} to resume (no {SEARCH_FILE} of scenario_search)")
        request = resumed(request, settings)
        return request, replace(kept, settings=request.settings.document())
    if kept is not None and kept.settings:
        raise BatchError(f"{folder} holds a search already: finish it with --resume, or give another folder "
                         "with -o")
    record = SearchRecord(round=0, strategy="", settings=request.settings.document())
    _save(folder, record)                      # the settings first: a search stopped in round 1 resumes
    return request, record


def run_search(request: SearchRequest) -> int:
    """Run (or resume) the search of ``request``; returns the exit code."""
    from executor.batch.orchestration import output_folder
    from executor.output.folder_lock import FolderBusy, FolderLock

    if not request.resume:           # a scenario that does not parse leaves no search behind to --resume
        rounds.first_strategy(request.settings.scenario, request.settings.round_size)
    folder = Path(output_folder(request.output_dir))
    try:
        lock = FolderLock(folder, "scenario_search").acquire(request.wait, on_wait=say)
    except FolderBusy as exc:
        raise BatchError(f"{exc}; nothing was run") from None
    with lock:
        request, record = _start(request, folder)
        store = QueueStore.open(request.store)
        previous = signal.signal(signal.SIGTERM, _interrupt)    # between batches SIGTERM stops as Ctrl-C does
        try:
            return _rounds(request, folder, record, store)
        except (KeyboardInterrupt, rounds.SearchInterrupted):
            say(f"interrupted: the search stopped before its round ended; finish it with "
                f"scenario_search --resume -o {request.output_dir}")
            return EXIT_STOPPED
        finally:
            signal.signal(signal.SIGTERM, previous)
            store.close()


def _interrupt(_signum: int, _frame: object) -> None:
    raise KeyboardInterrupt


def _rounds(request: SearchRequest, folder: Path, record: SearchRecord, store: QueueStore) -> int:
    settings = request.settings
    say(f"search {Path(settings.scenario).name}: goal {settings.goal}, budget {settings.budget} run(s), "
        f"{settings.round_size} a round, seed {settings.seed}"
        + (f"; resuming after round {len(record.rounds)}" if request.resume and record.rounds else ""))
    reporter = _QuietReporter()
    counted_all = False           # whether the record's estimate was made from every round run
    while True:
        used = sum(r.runs for r in record.rounds)
        if used >= settings.budget or record.estimate.done:
            break
        place = rounds.RoundPlace.of(str(folder), len(record.rounds) + 1)
        batch = rounds.round_batch(store, place)
        if batch is None:
            strategy = _strategy(request, place)
            sources = tuple(rounds.RoundPlace.of(str(folder), r.round).results for r in record.rounds)
            samples = min(settings.round_size, settings.budget - used)
            rounds.write_variants(rounds.variation_request(request, place, strategy, samples, sources),
                                  show=request.debug)
            estimate = read_search_record(place.variants)
            if estimate is not None and estimate.estimate.done and record.rounds:
                record = _estimated(record, estimate)       # the goal is met by the rounds run: none more
                counted_all = True
                break
            batch = rounds.open_batch(store, request, place)
        else:
            strategy = _round_strategy(place, request)
        ran = rounds.run_batch(store, batch, request, reporter)
        if ran.signum is not None:
            say(f"round {place.number}: interrupted; finish it with scenario_search --resume -o "
                f"{request.output_dir}")
            return EXIT_INTERRUPTED.get(ran.signum, 128 + int(ran.signum))
        estimate = read_search_record(place.variants)
        record = replace(_estimated(record, estimate) if estimate is not None else record,
                         round=place.number, strategy=strategy,
                         rounds=(*record.rounds, RoundSummary(place.number, strategy, ran.runs, ran.failed)))
        _save(folder, record)
        basis = f"estimate from {record.runs_read} earlier run(s): " if estimate is not None and record.runs_read else ""
        say(f"round {place.number} ({strategy}): {ran.runs} run(s), {ran.failed} not passed; "
            f"{used + ran.runs} of {settings.budget} run(s); {basis}{estimate_summary(record.estimate)}")
    if record.rounds and not counted_all:
        record = _estimated(record, rounds.final_estimate(request, folder, record.rounds))
    _save(folder, record)
    _finish(record, folder)
    return EXIT_DONE


def _strategy(request: SearchRequest, place: rounds.RoundPlace) -> str:
    """Round 1: a plain sampler; later rounds: the goal."""
    if place.number == 1:
        return rounds.first_strategy(request.settings.scenario, request.settings.round_size)
    return request.settings.goal


def _round_strategy(place: rounds.RoundPlace, request: SearchRequest) -> str:
    """The strategy of a round resumed after its variants were written: its estimate says, else as chosen."""
    kept = read_search_record(place.variants)
    return kept.strategy if kept is not None and kept.strategy else _strategy(request, place)


def _estimated(record: SearchRecord, round_record: SearchRecord) -> SearchRecord:
    """``record`` with the estimate (and what it was made from) of a round's ``search.json``."""
    return replace(record, sources=round_record.sources, runs_read=round_record.runs_read,
                   objective=round_record.objective, maximise=round_record.maximise,
                   estimate=round_record.estimate)


def _finish(record: SearchRecord, folder: Path) -> None:
    """The search's last words: the runs spent, the rounds, and the estimate."""
    runs = sum(r.runs for r in record.rounds)
    failed = sum(r.failed for r in record.rounds)
    say(f"search done: {runs} run(s) in {len(record.rounds)} round(s), {failed} not passed; "
        f"{folder / SEARCH_FILE}")
    estimate: Estimate = record.estimate
    for line in estimate_lines(estimate):
        say(f"  {line}")
