"""The work behind ``scenario_variation``: plan, report, write the ``.sce`` files and record them in the store.

Order matters for "bad input loses nothing already written": the input is parsed and every value
checked, and the store opened, *before* an earlier generation in the output folder is removed.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

#: Up to this many variants, each written file is named on the terminal.
LIST_FILES_UP_TO = 16
#: Skipped combinations listed one by one (after the per-value report) up to this many.
LIST_SKIPPED_UP_TO = 10


class VariationStoreError(Exception):
    """The store cannot be opened or written while recording a variation run."""


def _echo(message: str = "", err: bool = False) -> None:
    click.echo(message, err=err)


def _read_documents(path: str | None) -> list[dict] | None:
    if path is None:
        return None
    from coverage_engine.parameters import read_parameter_documents

    return read_parameter_documents(path)


def _describe(plan) -> None:
    """Say what will be varied (or that nothing is)."""
    if not plan.dimensions and plan.documents is None:
        _echo(f"{plan.path}: no keep(... in [...]) constraint: exactly one concrete model")
        return
    for dim in plan.dimensions:
        values = ", ".join(c.text for c in dim.choices)
        _echo(f"{dim.location}: {dim.key}: {len(dim.choices)} values [{values}]")
    if plan.documents is not None:
        _echo(f"parameter file: {len(plan.documents)} documents")
    sizes = " x ".join(str(n) for n in plan.sizes)
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
    """rich progress bar on a terminal (unless NO_COLOR), a few plain lines otherwise."""

    def __init__(self, total: int) -> None:
        self.total = total
        self.done = 0
        self._rich = None
        self._next_plain = total // 4 if total >= 20000 else total + 1
        if total >= 2000 and sys.stderr.isatty() and not os.environ.get("NO_COLOR"):
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

            self._rich = Progress("writing", BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                                  console=Console(stderr=True), transient=True)
            self._task = self._rich.add_task("variants", total=total)
            self._rich.start()

    def advance(self) -> None:
        self.done += 1
        if self._rich is not None:
            if self.done % 500 == 0 or self.done == self.total:
                self._rich.update(self._task, completed=self.done)
        elif self.done >= self._next_plain:
            _echo(f"... {self.done} of {self.total} combinations")
            self._next_plain += max(self.total // 4, 1)

    def close(self) -> None:
        if self._rich is not None:
            self._rich.stop()


def run(scenario: str, options: dict) -> int:
    """Generate (or list) the variants of ``scenario``; returns the exit code."""
    from coverage_engine.variation.plan import plan_variation

    path = Path(scenario)
    documents = _read_documents(options["scenario_parameter_file"])
    plan = plan_variation(path, documents)
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
    from store.variants import VariantRecord, record_variation

    output_dir = Path(options["output_dir"])
    # Files of the new generation overwrite those of the same name in place (far cheaper than
    # delete + create on most file systems); the rest of the earlier generation is removed afterwards.
    old = {p.name: p for p in earlier_generation(output_dir)}
    if old:
        _echo(f"replacing {len(old)} .sce file(s) of an earlier generation in {output_dir}/")
    progress = _Progress(plan.total)
    debug, log_model, verbose = options["debug"], options["log_model"], plan.total <= LIST_FILES_UP_TO
    counts = {"written": 0, "skipped": 0}

    def records():
        for item in generate(plan, output_dir, existing=frozenset(old)):
            progress.advance()
            if item.rejection is not None:
                counts["skipped"] += 1
                if counts["skipped"] <= LIST_SKIPPED_UP_TO or debug:
                    values = ", ".join(f"{k} = {v}" for k, v in plan.shown_assignment(item.choices).items())
                    _echo(f"skipped variant {item.index}: {values}", err=True)
                continue
            counts["written"] += 1
            old.pop(os.path.basename(item.path), None)
            if verbose or debug:
                _echo(f"wrote {os.path.relpath(item.path)}")
            if log_model:
                _log_model(plan, item)
            yield VariantRecord(index=item.index, scenario=plan.scenario, assignment=item.assignment_json,
                                sce_text=item.sce_text, file_path=item.path, content_hash=item.content_hash)

    store_options = {k: v for k, v in options.items() if k != "store"}
    store_options["source"] = str(plan.path)
    try:
        record_variation(engine, source_path=str(plan.path.resolve()), source_sha256=source_sha256(plan.text),
                         source_text=plan.text, options=store_options,
                         output_dir=str(output_dir.resolve()), records=records(), skipped=plan.total - plan.valid_count())
    except StoreError as exc:
        raise VariationStoreError(f"{exc} (the .sce files written so far are in {output_dir}/; "
                               "files of the earlier generation were kept)") from exc
    finally:
        progress.close()
    # Only a generation that was written and recorded completely replaces the earlier one.
    remove_files(list(old.values()))
    skipped = counts["skipped"]
    if skipped > LIST_SKIPPED_UP_TO and not debug:
        _echo(f"... {skipped - LIST_SKIPPED_UP_TO} more skipped variants (-d lists all)", err=True)
    summary = f"wrote {counts['written']} scenario file(s) to {output_dir}/"
    if skipped:
        summary += f"; {skipped} combination(s) skipped because they do not resolve"
    _echo(summary)
    return 1 if skipped else 0


_resolvers: dict = {}


def _log_model(plan, item) -> None:
    """``-l``: resolve this variant on its own and print its model (slow path, one resolution each)."""
    from coverage_engine.errors import OscError
    from coverage_engine.printer import format_model
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
