"""The work behind ``scenario_variation``: plan, report, write the ``.sce`` files and record them in the store.

Order matters for "bad input loses nothing already written": the input is parsed and every value
checked, and the store opened, *before* an earlier generation in the output folder is removed.
"""

from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path

import click

#: Up to this many variants, each written file is named on the terminal.
LIST_FILES_UP_TO = 16
#: Skipped combinations listed one by one (after the per-value report) up to this many.
LIST_SKIPPED_UP_TO = 10
#: Exit code of a run stopped by SIGINT or SIGTERM (what shells report for Ctrl-C).
EXIT_INTERRUPTED = 130


#: Default of ``--max-variants``: more combinations than this are refused unless the limit is raised.
DEFAULT_MAX_VARIANTS = 10_000_000


class VariationStoreError(Exception):
    """The store cannot be opened or written while recording a variation run."""


class TooManyVariants(Exception):
    """The file has more combinations than ``--max-variants`` allows."""


def _size(n: float) -> str:
    for unit in ("bytes", "KB", "MB", "GB", "TB", "PB"):
        if n < 1024:
            return f"{n:.0f} {unit}"
        n /= 1024
    return f"{n:.3g} EB"


def _slot_sizes(plan) -> list[int]:
    """Choices per independent slot: keeps on the same parameter count as one (their joint values)."""
    return [slot.count for slot in plan.slots]


def _echo(message: str = "", err: bool = False) -> None:
    click.echo(message, err=err)


def _read_documents(path: str | None) -> list[dict] | None:
    if path is None:
        return None
    from coverage_engine.files.parameters import read_parameter_documents

    return read_parameter_documents(path)


def _describe(plan) -> None:
    """Say what will be varied (or that nothing is)."""
    if not plan.dimensions and plan.documents is None:
        _echo(f"{plan.path}: no keep(... in [...]) constraint: exactly one concrete model")
        return
    first_of = {}
    for slot in plan.slots:
        for dim in slot.dims[1:]:
            first_of[dim] = slot.dims[0]
    for i, dim in enumerate(plan.dimensions):
        values = ", ".join(c.text for c in dim.choices)
        joint = ""
        if i in first_of:
            other = plan.dimensions[first_of[i]]
            joint = f" (the same parameter as line {other.location.line}: checked together, one dimension)"
        _echo(f"{dim.location}: {dim.key}: {len(dim.choices)} values [{values}]{joint}")
    if plan.documents is not None:
        _echo(f"parameter file: {len(plan.documents)} documents")
    sizes = " x ".join(str(n) for n in _slot_sizes(plan))
    _echo(f"{plan.total} combinations ({sizes}), {plan.resolutions} resolutions to check the values")


def _report_rejections(plan) -> None:
    for rejection in plan.rejections:
        values = ", ".join(f"{k} = {v}" for k, v in rejection.shown.items())
        where = f"{rejection.location}: " if rejection.location is not None else f"{plan.path}: "
        _echo(f"{where}error: {values} does not resolve; {rejection.skipped} combination(s) with it skipped",
              err=True)
        _echo("  " + rejection.error.render().replace("\n", "\n  "), err=True)


def _list(plan) -> int:
    stem = plan.path.stem
    skipped = 0
    for index, choices, rejection in plan.combinations():
        assignment = ", ".join(f"{k} = {v}" for k, v in plan.shown_assignment(choices).items())
        if rejection is None:
            _echo(f"{stem}{index}: {assignment or '(no varied parameter)'}")
        else:
            skipped += 1
            _echo(f"{stem}{index}: {assignment} (skipped: does not resolve)")
    _echo(f"{plan.total - skipped} variants would be generated" + (f", {skipped} skipped" if skipped else ""))
    return 1 if skipped else 0


def _open_store(url: str | None):
    from store.database import StoreError, ensure_schema, open_engine, store_url
    from store.variants import TABLES

    try:
        engine = open_engine(store_url(url))
        ensure_schema(engine, TABLES)
    except StoreError as exc:
        raise VariationStoreError(str(exc)) from exc
    return engine


class _Progress:
    """rich progress bar on a terminal (unless NO_COLOR); elsewhere a plain line every few seconds."""

    #: Seconds between two plain progress lines.
    PLAIN_EVERY = 5.0

    def __init__(self, total: int) -> None:
        self.total = total
        self.done = 0
        self._rich = None
        self._started = time.monotonic()
        self._next_plain = self._started + self.PLAIN_EVERY
        if total >= 2000 and sys.stderr.isatty() and not os.environ.get("NO_COLOR"):
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._rich = Progress("writing", BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                                  TimeRemainingColumn(), console=Console(stderr=True), transient=True)
            self._task = self._rich.add_task("variants", total=total)
            self._rich.start()

    def advance(self) -> None:
        self.done += 1
        if self.done & 255 and self.done != self.total:
            return
        if self._rich is not None:
            self._rich.update(self._task, completed=self.done)
            return
        now = time.monotonic()
        if now >= self._next_plain and self.done != self.total:
            self._next_plain = now + self.PLAIN_EVERY
            rate = self.done / max(now - self._started, 1e-9)
            _echo(f"... {self.done} of {self.total} combinations ({self.done * 100 / self.total:.2g} %), "
                  f"{rate:,.0f}/s, about {_duration((self.total - self.done) / rate)} left")

    def close(self) -> None:
        if self._rich is not None:
            self._rich.stop()


def _duration(seconds: float) -> str:
    """``42 s``, ``3 min 20 s``, ``5 h 02 min``, ``12 days``, ``3.2e+07 years``: for ETAs."""
    if seconds < 60:
        return f"{seconds:.0f} s"
    if seconds < 3600:
        return f"{seconds // 60:.0f} min {seconds % 60:02.0f} s"
    if seconds < 86400 * 2:
        return f"{seconds // 3600:.0f} h {seconds % 3600 // 60:02.0f} min"
    if seconds < 86400 * 365 * 2:
        return f"{seconds / 86400:.0f} days"
    return f"{seconds / (86400 * 365.25):.3g} years"


class _StopRequest:
    """While active, SIGINT and SIGTERM only ask the generation to stop before the next variant.

    The batch under way is then recorded and written, so every file on disk has its store row.
    """

    def __init__(self) -> None:
        self.signal: int | None = None
        self._saved: dict[int, object] = {}

    def __call__(self) -> bool:
        return self.signal is not None

    def _handle(self, signum, _frame) -> None:
        self.signal = signum

    def __enter__(self) -> _StopRequest:
        import threading

        if threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM):
                self._saved[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, *exc_info) -> None:
        for signum, handler in self._saved.items():
            signal.signal(signum, handler)


def run(scenario: str, options: dict) -> int:
    """Generate (or list) the variants of ``scenario``; returns the exit code."""
    from coverage_engine.variation.plan import build_plan, check_plan

    path = Path(scenario)
    documents = _read_documents(options["scenario_parameter_file"])
    plan = build_plan(path, documents)
    limit = options.get("max_variants") or DEFAULT_MAX_VARIANTS
    if plan.total > limit:
        sizes = " x ".join(str(n) for n in _slot_sizes(plan))
        raise TooManyVariants(
            f"{plan.path}: error: {plan.total} combinations ({sizes}) are more than --max-variants ({limit}); "
            f"nothing was written\nhint: list fewer values, or to generate them all anyway run again with "
            f"--max-variants {plan.total} (one .sce file each, about {_size(plan.total * 700)} on disk)")
    check_plan(plan)
    _describe(plan)
    _report_rejections(plan)
    if options["list"]:
        return _list(plan)
    valid = plan.valid_count()
    if valid == 0:
        _echo(f"error: none of the {plan.total} combinations resolves; nothing written", err=True)
        return 1
    engine = _open_store(options["store"])
    return _write(plan, options, engine)


def _write(plan, options: dict, engine) -> int:
    from coverage_engine.variation.output import earlier_generation, generate, remove_files, source_sha256
    from store.database import StoreError
    from store.variants import VariantRecord, VariationRecorder

    output_dir = Path(options["output_dir"])
    # Files of the new generation overwrite those of the same name in place (far cheaper than
    # delete + create on most file systems); the rest of the earlier generation is removed afterwards.
    old = {p.name: p for p in earlier_generation(output_dir)}
    if old:
        _echo(f"replacing {len(old)} .sce file(s) of an earlier generation in {output_dir}/")
    debug, log_model, verbose = options["debug"], options["log_model"], plan.total <= LIST_FILES_UP_TO
    counts = {"skipped": 0}
    store_options = {k: v for k, v in options.items() if k != "store"}
    store_options["source"] = str(plan.path)
    kept = "files of the earlier generation were kept"
    try:
        recorder = VariationRecorder(
            engine, source_path=str(plan.path.resolve()), source_sha256=source_sha256(plan.text),
            source_text=plan.text, options=store_options, output_dir=str(output_dir.resolve()),
            skipped=plan.total - plan.valid_count())
    except StoreError as exc:
        raise VariationStoreError(f"{exc} (nothing was written)") from exc
    scenario = plan.scenario

    def record(batch) -> None:
        recorder.add([VariantRecord(index=item.index, scenario=scenario, assignment=item.assignment_json,
                                    sce_text=item.sce_text, file_path=item.path, content_hash=item.content_hash)
                      for item in batch])

    def on_item(item) -> None:
        progress.advance()
        if item.rejection is not None:
            counts["skipped"] += 1
            if counts["skipped"] <= LIST_SKIPPED_UP_TO or debug:
                values = ", ".join(f"{k} = {v}" for k, v in plan.shown_assignment(item.choices).items())
                _echo(f"skipped variant {item.index}: {values}", err=True)
            return
        old.pop(os.path.basename(item.path), None)
        if verbose or debug:
            _echo(f"wrote {os.path.relpath(item.path)}")
        if log_model:
            _log_model(plan, item)

    progress = _Progress(plan.total)
    try:
        with _StopRequest() as stop:
            result = generate(plan, output_dir, existing=frozenset(old), record=record, on_item=on_item,
                              stop=stop)
            recorder.finish(complete=not result.stopped)
    except StoreError as exc:
        raise VariationStoreError(f"{exc} (the .sce files written so far are in {output_dir}/ and recorded; "
                                  f"{kept})") from exc
    finally:
        progress.close()
    skipped = counts["skipped"]
    if result.stopped:
        name = signal.Signals(stop.signal).name if stop.signal else "a stop request"
        _echo(f"interrupted ({name}): wrote {result.written} of {plan.valid_count()} scenario file(s) to "
              f"{output_dir}/, all {result.written} recorded in the store"
              + (f"; {kept}" if old else ""), err=True)
        return EXIT_INTERRUPTED
    # Only a generation that was written and recorded completely replaces the earlier one.
    remove_files(list(old.values()))
    if skipped > LIST_SKIPPED_UP_TO and not debug:
        _echo(f"... {skipped - LIST_SKIPPED_UP_TO} more skipped variants (-d lists all)", err=True)
    summary = f"wrote {result.written} scenario file(s) to {output_dir}/"
    if skipped:
        summary += f"; {skipped} combination(s) skipped because they do not resolve"
    _echo(summary)
    return 1 if skipped else 0


_resolvers: dict = {}


def _log_model(plan, item) -> None:
    """``-l``: resolve this variant on its own and print its model (slow path, one resolution each)."""
    from coverage_engine.errors import OscError
    from coverage_engine.resolve.printer import format_model
    from coverage_engine.variation.plan import default_resolver

    resolver = _resolvers.get(plan.path)
    if resolver is None:
        resolver = _resolvers[plan.path] = default_resolver(plan.path)
    try:
        model = resolver(plan.concrete_text(item.choices), plan.overrides(item.choices))
    except OscError as exc:
        _echo(f"variant {item.index}: {exc.render()}", err=True)
        return
    _echo(f"--- variant {item.index} ({os.path.relpath(item.path)})")
    _echo(format_model(model))
