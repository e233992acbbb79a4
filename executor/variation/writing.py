"""The last stage of ``scenario_variation``: write the chosen variants' ``.sce`` files and record each in the store.

Order matters for "bad input loses nothing already written": the names are checked and the output
folder surveyed *before* anything is touched (a file there that no generation of this source wrote
stops the run), each batch of files is written before its store rows are committed (so no row names a
file that is not there), and the earlier generation's files left over are removed only once the new
one is written and recorded completely. SIGINT and SIGTERM stop before the next variant, after the
batch under way is written and recorded (:class:`StopRequest`).
"""

from __future__ import annotations

import dataclasses
import os
import signal
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from coverage_engine.errors import OscError, UserError
from coverage_engine.location import Location
from coverage_engine.suffixes import SCE_SUFFIX
from executor.output.terminal import printable
from executor.variation import report
from executor.variation.report import echo

if TYPE_CHECKING:
    from sqlalchemy import Engine

    from coverage_engine.variation.covering import TupleCoverage
    from coverage_engine.variation.output import Generated, GenerationResult
    from coverage_engine.variation.plan import Resolve, VariationPlan
    from executor.variation.request import VariationRequest
    from store.variants import VariationRecorder

#: Up to this many variants, each written file is named on the terminal.
LIST_FILES_UP_TO = 16
#: Skipped combinations listed one by one (after the per-value report) up to this many.
LIST_SKIPPED_UP_TO = 10
#: Exit code of a run stopped by SIGINT or SIGTERM (what shells report for Ctrl-C).
EXIT_INTERRUPTED = 130
#: What a failed or stopped generation says of the earlier one.
_KEPT = "files of the earlier generation were kept"


class VariationStoreError(UserError):
    """The store cannot be opened or written while recording a variation run."""


class OutputNameTooLong(OscError):
    """the variants' file names would exceed what the file system allows"""


class VariantsNotWritten(OscError):
    """a variant's file could not be written (disk full, permission, file system limit)"""


class ForeignFilesInOutput(OscError):
    """files in the output folder that this generation would replace but did not write"""


def write_variants(plan: VariationPlan, request: VariationRequest, engine: Engine, seed: int | None = None,
                   tuples: TupleCoverage | None = None) -> int:
    """Write and record every valid variant of ``plan`` into ``request.output_dir``; returns the exit code."""
    from coverage_engine.variation.output import VariantWriteError, generate, remove_files
    from store.database import StoreError

    output_dir = Path(request.output_dir)
    _check_names(plan, output_dir)
    old = _earlier_files(plan, output_dir, adding=plan.adds_to_earlier)
    recorder = _open_recorder(plan, request, engine, seed, tuples)
    listing = _Listing(plan, request, old)
    try:
        with StopRequest() as stop:
            try:
                result = generate(plan, output_dir, existing=frozenset(old), record=listing.recording(recorder),
                                  on_item=listing.show, stop=stop)
            except VariantWriteError as exc:
                recorder.finish(complete=False)
                cause = exc.cause
                what = f"cannot write {cause.filename}" if cause.filename else "cannot write the variant files"
                raise VariantsNotWritten(
                    f"{what}: {cause.strerror or cause}; {exc.recorded} of {plan.valid_count()} variant(s) were "
                    f"written (and recorded) before it stopped" + (f"; {_KEPT}" if old else ""),
                    Location.whole_file(str(plan.path)),
                    hint="make room (or write to another folder with -o) and run again: the files written "
                         "now are replaced") from None
            recorder.finish(complete=not result.stopped and not plan.adds_to_earlier)
    except StoreError as exc:
        raise VariationStoreError(f"{exc} (the .sce files recorded so far are in {output_dir}/; "
                                  f"{_KEPT})") from exc
    finally:
        listing.progress.close()
    if result.stopped:
        name = signal.Signals(stop.signal).name if stop.signal else "a stop request"
        echo(f"interrupted ({name}): wrote {result.written} of {plan.valid_count()} scenario file(s) to "
             f"{output_dir}/, all {result.written} recorded in the store"
             + (f"; {_KEPT}" if old else ""), err=True)
        return EXIT_INTERRUPTED
    # Only a generation that was written and recorded completely replaces the earlier one.
    remove_files(list(old.values()))
    return _summarise(plan, request, result, listing.skipped)


def _check_names(plan: VariationPlan, output_dir: Path) -> None:
    """:class:`OutputNameTooLong` when the last variant's file name would be longer than the folder allows."""
    longest = f"{plan.path.stem}{max(plan.first_index + plan.total - 1, 0)}{SCE_SUFFIX}"
    limit = _name_max(output_dir)
    if len(os.fsencode(longest)) > limit:
        raise OutputNameTooLong(
            f"the variant files would be named up to '{longest[:40]}…{longest[-12:]}' ({len(os.fsencode(longest))} "
            f"bytes), longer than the {limit} bytes a file name may have in {output_dir}/; nothing was written",
            Location.whole_file(str(plan.path)), hint="give the .osc file a shorter name")


def _earlier_files(plan: VariationPlan, output_dir: Path, adding: bool) -> dict[str, Path]:
    """The files of an earlier generation of the same source that this one replaces (by name).

    Only what an earlier generation of the same source wrote is replaced; a file of the same name that
    it did not write (hand-written, another tool's, a symbolic link) stops the run before anything is
    written. Files of the new generation overwrite those of the same name in place (far cheaper than
    delete + create on most file systems); the rest is removed afterwards. ``adding`` (``--only-new``)
    adds to the earlier runs' files and replaces none of them.
    """
    from coverage_engine.variation.output import survey_output

    survey = survey_output(output_dir, plan.path, plan.total, plan.first_index)
    foreign = survey.foreign
    if foreign:
        shown = ", ".join(printable(p.name) for p in foreign[:3]) + (f" and {len(foreign) - 3} more"
                                                                      if len(foreign) > 3 else "")
        raise ForeignFilesInOutput(
            f"{output_dir}/ holds {len(foreign)} file(s) named like variants of {plan.path.name} that "
            f"scenario_variation did not generate from it ({shown}); nothing was written",
            Location.whole_file(str(plan.path)),
            hint="move those files away, or write the variants to another folder with -o")
    old = {p.name: p for p in survey.earlier}
    others = _other_sce_files(output_dir, set(old))
    if adding:
        if old:
            echo(f"keeping {len(old)} .sce file(s) of earlier runs in {output_dir}/; the variants they hold are "
                 "not written again")
        old = {}
    elif old:
        echo(f"replacing {len(old)} .sce file(s) of an earlier generation in {output_dir}/")
    if others:
        echo(f"leaving {others} other .sce file(s) in {output_dir}/ untouched (not variants of {plan.path.name})")
    return old


def _open_recorder(plan: VariationPlan, request: VariationRequest, engine: Engine, seed: int | None,
                   tuples: TupleCoverage | None) -> VariationRecorder:
    """The store's record of this run (its options, the source), before any file is written."""
    from coverage_engine.variation.output import source_sha256
    from store.database import StoreError
    from store.variants import VariationRecorder

    options = {**request.recorded_options(plan.path, seed), **({"tuples": dataclasses.asdict(tuples)} if tuples else {}),
               "variants": plan.total, "excluded_by_conditions": plan.excluded}
    try:
        return VariationRecorder(
            engine, source_path=str(plan.path.resolve()), source_sha256=source_sha256(plan.text),
            source_text=plan.text, options=options, output_dir=str(Path(request.output_dir).resolve()),
            skipped=plan.total - plan.valid_count())
    except StoreError as exc:
        raise VariationStoreError(f"{exc} (nothing was written)") from exc


@dataclass
class _Listing:
    """What the terminal is told per variant (written, skipped, its model with ``-l``) and the progress line."""

    plan: VariationPlan
    request: VariationRequest
    old: dict[str, Path]
    skipped: int = 0

    def __post_init__(self) -> None:
        self.progress = report.Progress(self.plan.total)
        self.verbose = self.request.debug or self.plan.total <= LIST_FILES_UP_TO
        self.log_model = _ModelLog(self.plan) if self.request.log_model else None

    def recording(self, recorder: VariationRecorder) -> Callable[[list[Generated]], None]:
        """The function that records a written batch's store rows."""
        from store.variants import VariantRecord

        scenario = self.plan.scenario

        def record(batch: list[Generated]) -> None:
            recorder.add([VariantRecord(index=item.index, scenario=scenario, assignment=item.assignment_json or "",
                                        sce_text=item.sce_text or "", file_path=item.path,
                                        content_hash=item.content_hash) for item in batch])

        return record

    def show(self, item: Generated) -> None:
        """One variant done: count it, name it (few variants, or ``-d``), print its model (``-l``)."""
        self.progress.advance()
        if item.rejection is not None:
            self.skipped += 1
            if self.skipped <= LIST_SKIPPED_UP_TO or self.request.debug:
                values = ", ".join(f"{k} = {v}" for k, v in self.plan.shown_assignment(item.choices).items())
                echo(f"skipped variant {item.index}: {values}", err=True)
            return
        path = item.path or ""
        self.old.pop(os.path.basename(path), None)
        if self.verbose:
            echo(f"wrote {os.path.relpath(path)}")
        if self.log_model is not None:
            self.log_model.show(item)


def _summarise(plan: VariationPlan, request: VariationRequest, result: GenerationResult, skipped: int) -> int:
    """The closing lines; the exit code (1 when a combination was skipped)."""
    output_dir = request.output_dir
    if skipped > LIST_SKIPPED_UP_TO and not request.debug:
        echo(f"... {skipped - LIST_SKIPPED_UP_TO} more skipped variants (-d lists all)", err=True)
    summary = f"wrote {result.written} scenario file(s) to {output_dir}/"
    if plan.adds_to_earlier:
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


class StopRequest:
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

    def __enter__(self) -> StopRequest:
        if threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM):
                self._saved[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, *exc_info: object) -> None:
        for signum, handler in self._saved.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]

