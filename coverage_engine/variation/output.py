"""Write the ``.sce`` files of a plan: clear an earlier generation, then stream one file per valid variant.

:func:`generate` works in batches: a batch's files are written (each whole, or not at all), then the
caller records the batch (store rows, committed), so a store row never names a file that was not
written, and a run stopped at any point leaves at most the batch under way written but not yet
recorded (its files carry the generation marker, so the next generation replaces them). Nothing is
kept per variant beyond two batches.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from array import array
from collections.abc import Callable, Container, Sequence
from dataclasses import dataclass
from pathlib import Path

from coverage_engine.domains import InputDomain, listed_domain
from coverage_engine.files.sce import is_sce_text
from coverage_engine.files.sce_writer import SceTemplate, relative_source_dir
from coverage_engine.lazy import NumberTexts, per_choice, row_texts
from coverage_engine.suffixes import SCE_SUFFIX
from coverage_engine.variation.drawn import DrawnChoices
from coverage_engine.variation.plan import Rejection, VariationPlan
from coverage_engine.variation.writer import FileWriter


@dataclass(frozen=True, slots=True)
class Generated:
    """One combination: written (``rejection`` None) or skipped (``rejection`` says why)."""

    index: int
    choices: tuple[int, ...]
    path: str | None
    sce_text: str | None
    content_hash: str | None
    assignment_json: str | None
    rejection: Rejection | None


def source_sha256(text: str) -> str:
    """SHA-256 (hex) of a source text as UTF-8."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def sce_template(plan: VariationPlan, output_dir: str | os.PathLike) -> SceTemplate:
    """The ``.sce`` template of ``plan`` for files written into ``output_dir``."""
    return SceTemplate(
        source=plan.path.name, source_sha256=source_sha256(plan.text),
        source_dir=relative_source_dir(plan.path.parent, output_dir), scenario=plan.scenario,
        chunks=list(plan.template.chunks), replacements=list(plan.template.replacements),
        keys=plan.keys, shown=plan.shown(), stored=plan.stored(), documents=plan.documents, note=plan.strategy_note,
        domains=plan_domains(plan), proposal=plan.proposal)


def plan_domains(plan: VariationPlan) -> list[InputDomain]:
    """What each dimension of ``plan`` declares (its listed values, or the range a sampler drew from):
    the ``# domain`` lines input coverage is measured against."""
    domains = []
    for dim in plan.dimensions:
        choices = dim.choices
        if isinstance(choices, DrawnChoices):
            spec = choices.spec
            domains.append(InputDomain(dim.key, low=spec.low, high=spec.high, unit=spec.unit,
                                       samples=plan.design_samples or len(choices)))
        else:
            domains.append(listed_domain(dim.key, [c.stored for c in choices]))
    return domains


@dataclass(frozen=True, slots=True)
class OutputSurvey:
    """What ``output_dir`` already holds under the names of ``source``'s variants.

    ``earlier``: the ``.sce`` files an earlier generation of the same source wrote (our marker, the same
    source file by name and folder) — to be replaced or removed. ``foreign``: entries under the name of
    one of the ``count`` new variants that no generation of it wrote (hand-written, another tool's, a
    symbolic link) — writing would replace them, or write through them, so the caller refuses to start.
    Variants of another ``.osc`` in the same folder are in neither list and are never touched.
    """

    earlier: list[Path]
    foreign: list[Path]


def survey_output(output_dir: str | os.PathLike, source: str | os.PathLike, count: int,
                  first: int = 0) -> OutputSurvey:
    """Sort the entries of ``output_dir`` named like variants of ``source`` (each file's head read once)."""
    folder = Path(output_dir)
    if not folder.is_dir():
        return OutputSurvey([], [])
    source = Path(source)
    start, end = len(source.stem), -len(SCE_SUFFIX)
    earlier, foreign = [], []
    for path in sorted(_named_like_variants(folder, source.stem)):
        ours = not path.is_symlink() and path.is_file() and written_from(path, source)
        if ours:
            earlier.append(path)
        elif first <= int(path.name[start:end]) < first + count \
                and str(int(path.name[start:end])) == path.name[start:end]:
            foreign.append(path)
    return OutputSurvey(earlier, foreign)


def _named_like_variants(folder: Path, stem: str) -> list[Path]:
    pattern = re.compile(re.escape(stem) + r"[0-9]+" + re.escape(SCE_SUFFIX))
    try:
        names = os.listdir(folder)
    except OSError:
        return []
    return [folder / name for name in names if pattern.fullmatch(name)]


#: How much of a ``.sce`` file's head is read to tell which source it was generated from.
_HEAD_BYTES = 8192
_HEAD_FIELD = re.compile(r'^(source|source_dir): (".*")$', re.MULTILINE)


def written_from(path: Path, source: Path) -> bool:
    """Whether ``path`` is a ``.sce`` that ``scenario_variation`` generated from ``source``."""
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            head = handle.read(_HEAD_BYTES)
    except OSError:
        return False
    if not is_sce_text(head):
        return False
    fields: dict[str, str] = {}
    for key, quoted in _HEAD_FIELD.findall(head):
        try:
            value = json.loads(quoted)
        except ValueError:
            return False
        if isinstance(value, str):
            fields.setdefault(key, value)
    if fields.get("source") != source.name or "source_dir" not in fields:
        return False
    recorded = (path.parent / fields["source_dir"]).resolve() if fields["source_dir"] else path.parent.resolve()
    return recorded == source.resolve().parent


def remove_files(paths: list[Path]) -> int:
    """Delete ``paths`` (missing ones are fine); returns how many were removed."""
    removed = 0
    for path in paths:
        try:
            path.unlink()
            removed += 1
        except FileNotFoundError:
            pass
    return removed


def _assignment_fragments(plan: VariationPlan) -> list[Sequence[str]]:
    """Per axis and choice, ``"key": value`` as it appears in the stored assignment JSON."""
    def fragments(key: str, values: Sequence[object]) -> Sequence[str]:
        prefix = f"{json.dumps(key, ensure_ascii=False)}: "
        if isinstance(values, array) and values.typecode == "d":
            return NumberTexts(values, prefix, "", _json_value)  # JSON spells a plain float as its repr
        return per_choice(values, lambda value: prefix + _json_value(value))

    return [fragments(key, values) for key, values in zip(plan.keys, plan.stored(), strict=True)]


def _json_value(value: object) -> str:
    """``json.dumps(value)``, with finite floats and ints written directly (the same text, 5x faster)."""
    kind = type(value)
    if kind is float and math.isfinite(value):  # type: ignore[arg-type]
        return repr(value)
    if kind is int:
        return str(value)
    return json.dumps(value, ensure_ascii=False)


def _same_content(path: str, data: bytes) -> bool:
    try:
        with open(path, "rb") as handle:
            return handle.read(len(data) + 1) == data
    except OSError:
        return False


#: From this many combinations on, files are written by a forked helper process (see writer.py).
BACKGROUND_FROM = 5000
#: Variants whose files are written, then whose store rows are committed, together.
BATCH_SIZE = 2000


@dataclass(frozen=True, slots=True)
class GenerationResult:
    """What :func:`generate` did: files written (and recorded), combinations skipped, whether it was stopped."""

    written: int
    skipped: int
    stopped: bool
    #: Combinations passed over because an earlier run wrote them (``--only-new``).
    held: int = 0


class VariantWriteError(Exception):
    """A variant's file could not be written; every variant whose file was written is recorded.

    ``cause`` is the :class:`OSError` (its ``filename`` the variant's path), ``recorded`` how many
    variants were written and recorded in all.
    """

    def __init__(self, cause: OSError, recorded: int) -> None:
        super().__init__(str(cause))
        self.cause, self.recorded = cause, recorded


@dataclass(slots=True)
class _Batch:
    """Variants sent to the writer, waiting for their files to be on disk before they are recorded."""

    items: list[Generated]
    checkpoint: int


class _BatchedRecording:
    """Sends batches of written variants to the file writer and records each once its files are on disk.

    At most two batches are under way: while the child writes one, the next is rendered.
    """

    def __init__(self, writer: FileWriter, record: Callable[[list[Generated]], None] | None,
                 on_item: Callable[[Generated], None] | None) -> None:
        self.writer, self.record, self.on_item = writer, record, on_item
        self.batch: list[Generated] = []
        self.unrecorded: list[_Batch] = []
        self.written = 0

    def settle(self, keep: int) -> None:
        """Record every sent batch but the last ``keep`` once its files are on disk."""
        while len(self.unrecorded) > keep:
            done = self.unrecorded[0]
            self.writer.wait(done.checkpoint)
            if self.record is not None:
                self.record(done.items)
            self.unrecorded.pop(0)
            self.written += len(done.items)
            if self.on_item is not None:
                for item in done.items:
                    self.on_item(item)

    def send(self) -> None:
        """Hand the batch made so far to the writer; record the one before it."""
        if self.batch:
            self.unrecorded.append(_Batch(self.batch.copy(), self.writer.checkpoint()))
            self.batch.clear()
        self.settle(keep=1)

    def finish(self) -> None:
        """Write and record everything sent."""
        self.send()
        self.writer.close()
        self.settle(keep=0)

    def salvage(self) -> None:
        """After a write failed: record exactly the files of the batches under way that hold their text
        (the others are absent or still an earlier generation's, whose rows stay right)."""
        self.writer.end_quietly()
        landed = [item for done in [*self.unrecorded, _Batch(self.batch, 0)] for item in done.items
                  if item.path and item.sce_text is not None and _same_content(item.path, item.sce_text.encode())]
        if landed and self.record is not None:
            self.record(landed)
            self.written += len(landed)


def generate(plan: VariationPlan, output_dir: str | os.PathLike, existing: Container[str] = (), *,
             record: Callable[[list[Generated]], None] | None = None,
             on_item: Callable[[Generated], None] | None = None,
             stop: Callable[[], bool] | None = None, batch_size: int = BATCH_SIZE) -> GenerationResult:
    """Write every valid combination of ``plan`` to ``output_dir``, in batches.

    For each batch of up to ``batch_size`` valid variants, their files are written (each whole, see
    :func:`~coverage_engine.variation.writer.write_file`), then ``record(batch)`` is called (the caller commits their
    store rows), then ``on_item`` is called for each (skipped combinations go to ``on_item`` as they
    come). So a store row never names a file that was not written. With the background writer the
    next batch is rendered while the child writes the last one, and a batch is recorded once the
    child confirms its files. If a file cannot be written, the variants of the batches under way
    whose files were written are recorded, and :class:`VariantWriteError` says how many are in all.
    ``stop()`` is asked before each combination; when it says yes, the batch made so far is written and recorded and generation
    ends (``stopped`` in the result). Nothing is kept per variant beyond two batches, so memory does
    not grow with their number.

    The folder is created if needed. Files are written as UTF-8 bytes exactly as hashed, so the
    stored content hash always matches the file. A file named in ``existing`` (names of the earlier
    generation) that already holds exactly the new text is left untouched: regenerating the same input
    rewrites nothing (truncating files is slow on some file systems, and mtimes stay meaningful).

    ``plan.held`` (``--only-new``): assignments (stored JSON text) already written by earlier runs; such a
    combination is passed over (counted in the result's ``held``), and the others are numbered from
    ``plan.first_index`` on without gaps.
    """
    held, first_index = plan.held, plan.first_index
    folder = Path(output_dir)
    folder.mkdir(parents=True, exist_ok=True)
    template = sce_template(plan, folder)
    prefix = str(folder.resolve() / plan.path.stem)
    fragments = _assignment_fragments(plan)
    sha256 = hashlib.sha256
    skipped = passed_over = 0
    stopped = False
    renumber = bool(held) or first_index > 0
    next_index = first_index            # when renumbering: the index of the next variant written
    writer = FileWriter(background=plan.total >= BACKGROUND_FROM)
    batches = _BatchedRecording(writer, record, on_item)
    try:
        for index, choices, rejection in plan.combinations():
            if stop is not None and stop():
                stopped = True
                break
            if rejection is not None:
                skipped += 1
                if on_item is not None:
                    on_item(Generated(index, choices, None, None, None, None, rejection))
                continue
            spelled = template.spell_row(choices)
            assignment = _assignment(fragments, choices, spelled)
            if renumber:
                if assignment in held:
                    passed_over += 1
                    continue
                index, next_index = next_index, next_index + 1
            text = template.render(index, choices, spelled)
            data = text.encode("utf-8")
            path = f"{prefix}{index}{SCE_SUFFIX}"
            batches.batch.append(Generated(index, choices, path, text, sha256(data).hexdigest(), assignment, None))
            earlier = bool(existing) and os.path.basename(path) in existing
            if not (earlier and _same_content(path, data)):
                writer.write(path, data, replace=earlier)
            if len(batches.batch) >= batch_size:
                batches.send()
        batches.finish()
    except OSError as exc:
        batches.salvage()
        raise VariantWriteError(exc, batches.written) from exc
    finally:
        writer.end_quietly()
    return GenerationResult(batches.written, skipped, stopped, passed_over)


def _assignment(fragments: list[Sequence[str]], choices: tuple[int, ...], spelled: list[str | None]) -> str:
    """The stored assignment JSON of one row (``spelled``: the row's drawn numbers, see ``SceTemplate.spell_row``)."""
    return "{" + ", ".join(row_texts(fragments, choices, spelled)) + "}"
