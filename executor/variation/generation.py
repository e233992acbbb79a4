"""The work behind ``scenario_variation``: plan, report, write the ``.sce`` files and record them in the store.

The language side (dimensions, the plan that checks each value once, the ``.sce`` files) is
:mod:`coverage_engine.variation`; this module runs it for one :class:`VariationRequest` and records
every written file in the store (:mod:`store.variants`), so it stands where the other commands'
orchestrators stand (``cli → executor → coverage_engine | store``).

Order matters for "bad input loses nothing already written": the input is parsed and every value
checked, and the store opened, *before* an earlier generation in the output folder is touched; it
is removed only once the new generation is written and recorded completely. Each batch of files is
written before its store rows are committed, so no row names a file that is not there. SIGINT and
SIGTERM stop the generation before the next variant, after the batch under way is written and
recorded, so every file on disk has its store row.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from coverage_engine.errors import OscError
from coverage_engine.location import Location
from executor.output.terminal import printable
from executor.variation import report
from executor.variation.report import echo
from executor.variation.request import DEFAULT_MAX_VARIANTS, VariationRequest
from executor.variation.writing import EXIT_INTERRUPTED, VariationStoreError, write_variants

if TYPE_CHECKING:
    from sqlalchemy import Engine

    from coverage_engine.variation.covering import TupleCoverage
    from coverage_engine.variation.plan import ParsedVariation, PlannedVariation, VariationPlan
    from coverage_engine.variation.strategies import StrategyOptions
    from executor.variation.search import AdaptiveRound
    from store.variant_history import HeldVariants

#: Bytes of one ``.sce`` file, roughly, for the disk-space estimate of ``--max-variants``.
SCE_FILE_BYTES = 700


class TooManyVariants(OscError):
    """more combinations than --max-variants allows"""


class OutputFolderBusy(OscError):
    """another scenario_variation (or batch) writes into the output folder"""


def run(request: VariationRequest) -> int:
    """Generate (or list) the variants of ``request.scenario``; returns the exit code.

    The stages of :mod:`coverage_engine.variation` in order: parse, design (:func:`_design`), check,
    choose (:func:`_choose`), then report and write (:func:`~executor.variation.writing.write_variants`).
    """
    from coverage_engine.variation import strategies
    from coverage_engine.variation.plan import parse_variation

    try:
        request.scenario.encode("utf-8")
    except UnicodeEncodeError:
        raise OscError(f"{printable(request.scenario)}: the file name is not UTF-8; rename the file (nothing was "
                       "written for it)") from None
    with _terminate_like_interrupt():
        documents = None
        if request.parameter_file is not None:
            from coverage_engine.files.parameters import read_parameter_documents

            documents = read_parameter_documents(request.parameter_file)
        seed = request.seed
        if seed is None and request.strategy != "full":
            import secrets

            seed = secrets.randbelow(2**31)
            echo(f"seed {seed} (pass --seed {seed} to make the same variants again)")
        options = strategies.StrategyOptions(request.strategy, request.strength, request.samples, seed or 0)
        parsed = parse_variation(Path(request.scenario), documents)
        _check_adaptive(request, Location.whole_file(str(parsed.path)))
        engine = _open_store(request.store) if request.only_new else None
        held = None
        if engine is not None:
            held = _held(parsed, request, engine)
            strategies.check_continuable(options, len(held.assignments), held.runs, Location.whole_file(str(parsed.path)))
        search = _search(parsed, request, seed or 0) if request.adaptive else None
        if search is not None and not search.planned.rows:
            return _nothing_proposed(request, search)
        plan, tuples = _choose(parsed, request, options, held, search)
        return _report_and_write(plan, request, engine, seed, tuples, search)


def _report_and_write(plan: VariationPlan, request: VariationRequest, engine: Engine | None, seed: int | None,
                      tuples: TupleCoverage | None, search: AdaptiveRound | None) -> int:
    """Say what was chosen; unless only listing, and all or nothing, write it under the output folder's lock."""
    report.describe(plan)
    if request.strategy != "full":
        echo(_strategy_summary(plan, request, tuples))
    report.report_rejections(plan)
    if request.list_only:
        return report.list_assignments(plan)
    if plan.rejections:
        # All or nothing: a typo in one value must not leave a partial set of variants that a
        # pipeline ignoring the exit code would report as the whole.
        bad = plan.total - plan.valid_count()
        echo(f"error: {bad} of {plan.total} combination(s) hold a value that does not resolve; nothing was "
             "written (every combination is checked before any file is written: fix the value(s) above)",
             err=True)
        return 1
    from executor.output.folder_lock import FolderBusy, FolderLock

    try:
        lock = FolderLock(request.output_dir, "scenario_variation").acquire(
            request.wait, on_wait=lambda text: echo(text, err=True))
    except FolderBusy as exc:
        raise OutputFolderBusy(f"{exc}; nothing was written", Location.whole_file(str(plan.path))) from None
    with lock:
        code = write_variants(plan, request, engine or _open_store(request.store), seed, tuples)
        if search is not None and code != EXIT_INTERRUPTED:
            from executor.variation.search import write_estimate

            echo(f"estimate kept in {printable(str(write_estimate(request.output_dir, search.record)))}")
        return code


def _check_adaptive(request: VariationRequest, where: Location) -> None:
    """``--from`` goes with an adaptive strategy, and an adaptive strategy needs ``--from``."""
    from coverage_engine.search import ADAPTIVE
    from coverage_engine.variation.strategies import StrategyError

    if request.adaptive and not request.from_results:
        raise StrategyError(f"--strategy {request.strategy} proposes from earlier results: give them with --from "
                            "RESULTS", where, hint="run a first round with --strategy lhs --samples N, run it with "
                                                   "scenario_batch_execution, then pass its results folder")
    if request.from_results and not request.adaptive:
        raise StrategyError(f"--from is read by the adaptive strategies ({', '.join(ADAPTIVE)}), not by "
                            f"--strategy {request.strategy}", where)


def _search(parsed: ParsedVariation, request: VariationRequest, seed: int) -> AdaptiveRound:
    """The adaptive strategy's round: the earlier runs read, the estimate printed, the proposals planned."""
    from coverage_engine.search.errors import SearchError
    from coverage_engine.search.propose import SearchOptions
    from executor.variation.search import adaptive_round

    if request.samples is None:
        raise SearchError(f"--strategy {request.strategy} needs --samples N (how many variants to propose)",
                          Location.whole_file(str(parsed.path)))
    options = SearchOptions(request.strategy, request.samples, seed, request.from_results, request.target,
                            request.round_number)
    return adaptive_round(parsed, options, request.store if request.from_store else None)


def _nothing_proposed(request: VariationRequest, search: AdaptiveRound) -> int:
    """An adaptive round with no point to try (its goal is met, or no hole is left): no variant is written, and
    the estimate is kept all the same, so the search loop reads that it is done."""
    from executor.variation.search import write_estimate

    echo("no variant proposed: " + ("the goal is met" if search.record.estimate.done else "nothing is left to try"))
    if not request.list_only:
        os.makedirs(request.output_dir, exist_ok=True)
        echo(f"estimate kept in {printable(str(write_estimate(request.output_dir, search.record)))}")
    return 0


def _design(parsed: ParsedVariation, request: VariationRequest, options: StrategyOptions,
            factor: int, search: AdaptiveRound | None = None) -> PlannedVariation:
    """The design stage: the points the request's strategy asks for (``factor`` x its samples for a sampler
    redrawing after the keep conditions left out too many), or those an adaptive round proposed. A plain
    strategy given a round number (the search loop's first round) writes the proposal line too."""
    from coverage_engine.proposals import Proposal
    from coverage_engine.variation import strategies
    from coverage_engine.variation.design import design

    if search is not None:
        return search.planned
    limit = request.max_variants or DEFAULT_MAX_VARIANTS
    proposal = Proposal(request.round_number, request.strategy) if request.round_number is not None else None
    planned = design(parsed, options, factor, proposal=proposal)
    wanted = planned.total if factor == 1 else options.samples or 0
    if wanted > limit and options.strategy not in strategies.COVERING:
        raise TooManyVariants(
            f"{wanted} combinations ({report.slot_sizes(planned)}) are more than --max-variants ({limit}); "
            "nothing was written", Location.whole_file(str(parsed.path)),
            hint=f"list fewer values, or to generate them all anyway run again with --max-variants "
                 f"{wanted} (one .sce file each, about {report.size_text(wanted * SCE_FILE_BYTES)} "
                 "on disk)")
    return planned


def _choose(parsed: ParsedVariation, request: VariationRequest, options: StrategyOptions,
            held: HeldVariants | None,
            search: AdaptiveRound | None = None) -> tuple[VariationPlan, TupleCoverage | None]:
    """Design, check and choose: the plan to write, and for a covering array the tuples it covers.

    A sampler whose draws the keep conditions thin out draws twice as many until ``--samples`` are left.
    """
    from coverage_engine.variation import strategies
    from coverage_engine.variation.checking import check_values
    from coverage_engine.variation.choice import choose_all, first_samples, only_new
    from coverage_engine.variation.covering import choose_covering, refuse_oversized

    limit = request.max_variants or DEFAULT_MAX_VARIANTS
    covering = options.strategy in strategies.COVERING
    tuples = None
    factor = 1
    while True:
        planned = _design(parsed, request, options, factor, search)
        if covering and options.t <= len(planned.sizes):   # (a strength beyond the dimensions is said later)
            refuse_oversized(planned, options, limit)      # before 2,000 values are checked
        checked = check_values(planned)
        if covering:
            seeds = strategies.rows_of(checked, held.assignments) if held is not None else ()
            plan, tuples = choose_covering(checked, options, seeds, limit=limit,
                                           tick=report.Ticker("building the covering array"))
            break
        chosen = first_samples(choose_all(checked), options, factor)
        if chosen is not None:
            plan = chosen
            break
        factor *= 2
    if held is not None:
        plan = only_new(plan, held.assignments, held.next_index)
    return plan, tuples


def _open_store(url: str | None) -> Engine:
    from store.database import StoreError, ensure_schema, open_engine, store_url
    from store.variants import TABLES

    try:
        engine = open_engine(store_url(url))
        ensure_schema(engine, TABLES)
    except StoreError as exc:
        raise VariationStoreError(str(exc)) from exc
    return engine


def _strategy_summary(plan: VariationPlan, request: VariationRequest, tuples: TupleCoverage | None) -> str:
    """One line: the strategy, how many variants it chose and, for a covering array, the tuples covered."""
    text = f"strategy {request.strategy}: {plan.total} variant(s) over {len(plan.sizes)} dimension(s)"
    if tuples is not None:
        text += (f"; {tuples.covered} of {tuples.coverable} coverable {tuples.strength}-tuples covered"
                 + (f" ({tuples.impossible} impossible: they hold a value that does not resolve"
                    + (", or break a keep condition)" if plan.constraints is not None else ")")
                    if tuples.impossible else ""))
    samples = request.samples or 0
    if request.strategy == "sobol" and samples & (samples - 1):
        text += f" (Sobol' points are balanced for a power of 2 samples, e.g. {1 << samples.bit_length()})"
    return text


def _held(plan: ParsedVariation, request: VariationRequest, engine: Engine) -> HeldVariants:
    """``--only-new``: what earlier runs of this source (path and text) wrote into the output folder."""
    from coverage_engine.variation.output import source_sha256
    from store.database import StoreError
    from store.variant_history import held_variants

    try:
        return held_variants(engine, source_path=str(plan.path.resolve()), source_sha256=source_sha256(plan.text),
                             output_dir=str(Path(request.output_dir).resolve()))
    except StoreError as exc:
        raise VariationStoreError(f"{exc} (nothing was written)") from exc


@contextmanager
def _terminate_like_interrupt() -> Iterator[None]:
    """While inside, SIGTERM stops the command like Ctrl-C does (exit 130, no traceback).

    While files are written, :class:`~executor.variation.writing.StopRequest` takes both signals over to stop cleanly.
    """
    def interrupt(_signum: int, _frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
