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

import dataclasses
import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from coverage_engine.errors import OscError
from coverage_engine.location import Location
from coverage_engine.suffixes import SCE_SUFFIX
from coverage_engine.variation.strategies import COVERING
from executor.output.terminal import printable
from executor.variation import report
from executor.variation.report import echo

if TYPE_CHECKING:
    from sqlalchemy import Engine

    from coverage_engine.variation.covering import TupleCoverage
    from coverage_engine.variation.output import Generated
    from coverage_engine.variation.plan import ParsedVariation, PlannedVariation, Resolve, VariationPlan
    from coverage_engine.variation.strategies import StrategyOptions
    from store.variant_history import HeldVariants

#: Default of ``--max-variants``: more combinations than this are refused unless the limit is raised.
DEFAULT_MAX_VARIANTS = 10_000_000
#: Up to this many variants, each written file is named on the terminal.
LIST_FILES_UP_TO = 16
#: Skipped combinations listed one by one (after the per-value report) up to this many.
LIST_SKIPPED_UP_TO = 10
#: Exit code of a run stopped by SIGINT or SIGTERM (what shells report for Ctrl-C).
EXIT_INTERRUPTED = 130
#: Bytes of one ``.sce`` file, roughly, for the disk-space estimate of ``--max-variants``.
SCE_FILE_BYTES = 700


class VariationStoreError(Exception):
    """The store cannot be opened or written while recording a variation run."""


class TooManyVariants(OscError):
    """more combinations than --max-variants allows"""


class OutputFolderBusy(OscError):
    """another scenario_variation (or batch) writes into the output folder"""


class OutputNameTooLong(OscError):
    """the variants' file names would exceed what the file system allows"""


class VariantsNotWritten(OscError):
    """a variant's file could not be written (disk full, permission, file system limit)"""


class ForeignFilesInOutput(OscError):
    """files in the output folder that this generation would replace but did not write"""


@dataclass(frozen=True)
class VariationRequest:
    """One ``scenario_variation`` call: the file to vary and the command line's options."""

    scenario: str
    output_dir: str = "out"
    parameter_file: str | None = None
    list_only: bool = False
    log_model: bool = False
    debug: bool = False
    store: str | None = None
    max_variants: int = DEFAULT_MAX_VARIANTS
    strategy: str = "full"
    strength: int = 2
    samples: int | None = None
    seed: int | None = None
    wait: bool = False
    only_new: bool = False

    def recorded_options(self, source: Path, seed: int | None = None) -> dict[str, object]:
        """The options kept with the run in the store, under the command line's names."""
        return {"output_dir": self.output_dir, "debug": self.debug, "log_model": self.log_model,
                "list": self.list_only, "scenario_parameter_file": self.parameter_file,
                "max_variants": self.max_variants, "source": str(source), "strategy": self.strategy,
                "strength": self.strength, "samples": self.samples, "seed": seed, "only_new": self.only_new}


def run(request: VariationRequest) -> int:
    """Generate (or list) the variants of ``request.scenario``; returns the exit code.

    The stages of :mod:`coverage_engine.variation` in order: parse, design (:func:`_design`), check,
    choose (:func:`_choose`), then report and write (:func:`_write`).
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
        engine = _open_store(request.store) if request.only_new else None
        held = None
        if engine is not None:
            held = _held(parsed, request, engine)
            strategies.check_continuable(options, len(held.assignments), held.runs, Location(str(parsed.path), 0, 0))
        plan, tuples = _choose(parsed, request, options, held)
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
            raise OutputFolderBusy(f"{exc}; nothing was written", Location(str(plan.path), 0, 0)) from None
        with lock:
            return _write(plan, request, engine or _open_store(request.store), seed, held, tuples)


def _design(parsed: ParsedVariation, request: VariationRequest, options: StrategyOptions,
            factor: int) -> PlannedVariation:
    """The design stage: the points the request's strategy asks for (``factor`` x its samples for a sampler
    redrawing after the keep conditions left out too many). An adaptive strategy plugs in here."""
    from coverage_engine.variation.design import design

    limit = request.max_variants or DEFAULT_MAX_VARIANTS
    planned = design(parsed, options, factor)
    wanted = planned.total if factor == 1 else options.samples or 0
    if wanted > limit and options.strategy not in COVERING:
        raise TooManyVariants(
            f"{wanted} combinations ({report.slot_sizes(planned)}) are more than --max-variants ({limit}); "
            "nothing was written", Location(str(parsed.path), 0, 0),
            hint=f"list fewer values, or to generate them all anyway run again with --max-variants "
                 f"{wanted} (one .sce file each, about {report.size_text(wanted * SCE_FILE_BYTES)} "
                 "on disk)")
    return planned


def _choose(parsed: ParsedVariation, request: VariationRequest, options: StrategyOptions,
            held: HeldVariants | None) -> tuple[VariationPlan, TupleCoverage | None]:
    """Design, check and choose: the plan to write, and for a covering array the tuples it covers.

    A sampler whose draws the keep conditions thin out draws twice as many until ``--samples`` are left.
    """
    from coverage_engine.variation import strategies
    from coverage_engine.variation.checking import check_values
    from coverage_engine.variation.choice import choose_all, first_samples, only_new
    from coverage_engine.variation.covering import choose_covering, refuse_oversized

    limit = request.max_variants or DEFAULT_MAX_VARIANTS
    covering = options.strategy in COVERING
    tuples = None
    factor = 1
    while True:
        planned = _design(parsed, request, options, factor)
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


def _write(plan: VariationPlan, request: VariationRequest, engine: Engine, seed: int | None = None,
           held: HeldVariants | None = None,
           tuples: TupleCoverage | None = None) -> int:
    from coverage_engine.variation.output import (
        VariantWriteError,
        generate,
        remove_files,
        source_sha256,
        survey_output,
    )
    from store.database import StoreError
    from store.variants import VariantRecord, VariationRecorder

    output_dir = Path(request.output_dir)
    # Files of the new generation overwrite those of the same name in place (far cheaper than
    # delete + create on most file systems); the rest of the earlier generation is removed afterwards.
    first = plan.first_index     # --only-new numbers after the earlier runs
    longest = f"{plan.path.stem}{max(first + plan.total - 1, 0)}{SCE_SUFFIX}"
    limit = _name_max(output_dir)
    if len(os.fsencode(longest)) > limit:
        raise OutputNameTooLong(
            f"the variant files would be named up to '{longest[:40]}…{longest[-12:]}' ({len(os.fsencode(longest))} "
            f"bytes), longer than the {limit} bytes a file name may have in {output_dir}/; nothing was written",
            Location(str(plan.path), 0, 0), hint="give the .osc file a shorter name")
    # Only what an earlier generation of the same source wrote is replaced; a file of the same name that
    # it did not write (hand-written, another tool's, a symbolic link) stops the run before anything is written.
    survey = survey_output(output_dir, plan.path, plan.total, first)
    foreign = survey.foreign
    if foreign:
        shown = ", ".join(printable(p.name) for p in foreign[:3]) + (f" and {len(foreign) - 3} more"
                                                                      if len(foreign) > 3 else "")
        raise ForeignFilesInOutput(
            f"{output_dir}/ holds {len(foreign)} file(s) named like variants of {plan.path.name} that "
            f"scenario_variation did not generate from it ({shown}); nothing was written",
            Location(str(plan.path), 0, 0),
            hint="move those files away, or write the variants to another folder with -o")
    old = {p.name: p for p in survey.earlier}
    others = _other_sce_files(output_dir, set(old))
    if held is not None:            # --only-new adds to the earlier runs' files; it replaces none of them
        if old:
            echo(f"keeping {len(old)} .sce file(s) of earlier runs in {output_dir}/; the variants they hold are "
                 "not written again")
        old = {}
    elif old:
        echo(f"replacing {len(old)} .sce file(s) of an earlier generation in {output_dir}/")
    if others:
        echo(f"leaving {others} other .sce file(s) in {output_dir}/ untouched (not variants of {plan.path.name})")
    debug, verbose = request.debug, plan.total <= LIST_FILES_UP_TO
    skipped = 0
    kept = "files of the earlier generation were kept"
    try:
        recorder = VariationRecorder(
            engine, source_path=str(plan.path.resolve()), source_sha256=source_sha256(plan.text),
            source_text=plan.text, options={**request.recorded_options(plan.path, seed),
                                            **({"tuples": dataclasses.asdict(tuples)} if tuples else {}),
                                            "variants": plan.total, "excluded_by_conditions": plan.excluded},
            output_dir=str(output_dir.resolve()), skipped=plan.total - plan.valid_count())
    except StoreError as exc:
        raise VariationStoreError(f"{exc} (nothing was written)") from exc
    scenario = plan.scenario
    log_model = _ModelLog(plan) if request.log_model else None

    def record(batch: list[Generated]) -> None:
        recorder.add([VariantRecord(index=item.index, scenario=scenario, assignment=item.assignment_json or "",
                                    sce_text=item.sce_text or "", file_path=item.path, content_hash=item.content_hash)
                      for item in batch])

    def on_item(item: Generated) -> None:
        nonlocal skipped
        progress.advance()
        if item.rejection is not None:
            skipped += 1
            if skipped <= LIST_SKIPPED_UP_TO or debug:
                values = ", ".join(f"{k} = {v}" for k, v in plan.shown_assignment(item.choices).items())
                echo(f"skipped variant {item.index}: {values}", err=True)
            return
        path = item.path or ""
        old.pop(os.path.basename(path), None)
        if verbose or debug:
            echo(f"wrote {os.path.relpath(path)}")
        if log_model is not None:
            log_model.show(item)

    progress = report.Progress(plan.total)
    try:
        with _StopRequest() as stop:
            try:
                result = generate(plan, output_dir, existing=frozenset(old), record=record, on_item=on_item,
                                  stop=stop)
            except VariantWriteError as exc:
                recorder.finish(complete=False)
                cause = exc.cause
                what = f"cannot write {cause.filename}" if cause.filename else "cannot write the variant files"
                raise VariantsNotWritten(
                    f"{what}: {cause.strerror or cause}; {exc.recorded} of {plan.valid_count()} variant(s) were "
                    f"written (and recorded) before it stopped" + (f"; {kept}" if old else ""), Location(str(plan.path), 0, 0),
                    hint="make room (or write to another folder with -o) and run again: the files written "
                         "now are replaced") from None
            recorder.finish(complete=not result.stopped and held is None)
    except StoreError as exc:
        raise VariationStoreError(f"{exc} (the .sce files recorded so far are in {output_dir}/; "
                                  f"{kept})") from exc
    finally:
        progress.close()
    if result.stopped:
        name = signal.Signals(stop.signal).name if stop.signal else "a stop request"
        echo(f"interrupted ({name}): wrote {result.written} of {plan.valid_count()} scenario file(s) to "
             f"{output_dir}/, all {result.written} recorded in the store"
             + (f"; {kept}" if old else ""), err=True)
        return EXIT_INTERRUPTED
    # Only a generation that was written and recorded completely replaces the earlier one.
    remove_files(list(old.values()))
    if skipped > LIST_SKIPPED_UP_TO and not debug:
        echo(f"... {skipped - LIST_SKIPPED_UP_TO} more skipped variants (-d lists all)", err=True)
    summary = f"wrote {result.written} scenario file(s) to {output_dir}/"
    if held is not None:
        summary = (f"wrote {result.written} new scenario file(s) to {output_dir}/; {result.held} variant(s) "
                   "earlier runs wrote were not written again")
    if skipped:
        summary += f"; {skipped} combination(s) skipped because they do not resolve"
    echo(summary)
    return 1 if skipped else 0


def _other_sce_files(folder: Path, ours: set[str]) -> int:
    """How many ``.sce`` files in ``folder`` this generation neither writes nor replaces."""
    try:
        return sum(1 for name in os.listdir(folder) if name.endswith(SCE_SUFFIX) and name not in ours)
    except OSError:
        return 0


def _name_max(folder: Path) -> int:
    """Longest file name (bytes) the file system of ``folder`` (or its nearest existing parent) accepts."""
    probe = folder
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    try:
        return int(os.pathconf(probe, "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):
        return 255


class _ModelLog:
    """``-l``: resolve each written variant on its own and print its model (slow path, one resolution each)."""

    def __init__(self, plan: VariationPlan) -> None:
        from coverage_engine.variation.plan import default_resolver

        self.plan = plan
        self.resolver: Resolve = default_resolver(plan.path)

    def show(self, item: Generated) -> None:
        from coverage_engine.resolve.printer import format_model

        plan = self.plan
        try:
            model = self.resolver(plan.concrete_text(item.choices), plan.overrides(item.choices))
        except OscError as exc:
            echo(f"variant {item.index}: {exc.render()}", err=True)
            return
        echo(f"--- variant {item.index} ({os.path.relpath(item.path or '')})")
        echo(format_model(model))


class _StopRequest:
    """While active, SIGINT and SIGTERM only ask the generation to stop before the next variant.

    The batch under way is then written and recorded, so every file on disk has its store row.
    """

    def __init__(self) -> None:
        self.signal: int | None = None
        self._saved: dict[int, object] = {}

    def __call__(self) -> bool:
        return self.signal is not None

    def _handle(self, signum: int, _frame: FrameType | None) -> None:
        self.signal = signum

    def __enter__(self) -> _StopRequest:
        if threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM):
                self._saved[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, *exc_info: object) -> None:
        for signum, handler in self._saved.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]


@contextmanager
def _terminate_like_interrupt() -> Iterator[None]:
    """While inside, SIGTERM stops the command like Ctrl-C does (exit 130, no traceback).

    While files are written, :class:`_StopRequest` takes both signals over to stop cleanly.
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
