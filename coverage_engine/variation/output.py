"""Write the ``.sce`` files of a plan: clear an earlier generation, then stream one file per valid variant.

:func:`generate` is a generator: each :class:`Generated` is yielded right after its file is written,
so the caller can record it (store rows, progress) while the next one is made, and nothing is kept.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Container, Iterator
from dataclasses import dataclass
from pathlib import Path

from coverage_engine.sce import SceTemplate, is_sce_text, relative_source_dir
from coverage_engine.variation.plan import Rejection, VariationPlan
from coverage_engine.variation.writer import FileWriter

#: The ``.sce`` suffix; files are named ``<source stem><index>.sce``.
SUFFIX = ".sce"


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
        chunks=list(plan.template.chunks), replacements=[list(r) for r in plan.template.replacements],
        keys=plan.keys, shown=plan.shown(), stored=plan.stored(), documents=plan.documents)


def earlier_generation(output_dir: str | os.PathLike) -> list[Path]:
    """The ``.sce`` files directly in ``output_dir`` (an earlier generation, to be replaced)."""
    folder = Path(output_dir)
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.suffix == SUFFIX and p.is_file())


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


def is_ours(path: Path) -> bool:
    """Whether ``path`` starts like a ``.sce`` we write (the reference tool's ``.sce`` does not)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            return is_sce_text(handle.read(64))
    except OSError:
        return False


def _assignment_fragments(plan: VariationPlan) -> list[list[str]]:
    """Per axis and choice, ``"key": value`` as it appears in the stored assignment JSON."""
    return [[f"{json.dumps(key, ensure_ascii=False)}: {json.dumps(value, ensure_ascii=False)}" for value in values]
            for key, values in zip(plan.keys, plan.stored(), strict=True)]


def _same_content(path: str, data: bytes) -> bool:
    try:
        with open(path, "rb") as handle:
            return handle.read(len(data) + 1) == data
    except OSError:
        return False


#: From this many combinations on, files are written by a forked helper process (see writer.py).
BACKGROUND_FROM = 5000


def generate(plan: VariationPlan, output_dir: str | os.PathLike,
             existing: Container[str] = ()) -> Iterator[Generated]:
    """Write every valid combination of ``plan`` to ``output_dir`` and yield each (also skipped ones).

    The folder is created if needed. Files are written as UTF-8 bytes exactly as hashed, so the
    stored content hash always matches the file. A file named in ``existing`` (names of the earlier
    generation) that already holds exactly the new text is left untouched: regenerating the same input
    rewrites nothing (truncating files is slow on some file systems, and mtimes stay meaningful).
    """
    folder = Path(output_dir)
    folder.mkdir(parents=True, exist_ok=True)
    template = sce_template(plan, folder)
    prefix = str(folder.resolve() / plan.path.stem)
    fragments = _assignment_fragments(plan)
    sha256 = hashlib.sha256
    with FileWriter(background=plan.total >= BACKGROUND_FROM) as writer:
        yield from _generate(plan, template, prefix, fragments, existing, writer, sha256)


def _generate(plan, template, prefix, fragments, existing, writer, sha256) -> Iterator[Generated]:
    for index, choices, rejection in plan.combinations():
        if rejection is not None:
            yield Generated(index, choices, None, None, None, None, rejection)
            continue
        text = template.render(index, choices)
        data = text.encode("utf-8")
        path = f"{prefix}{index}{SUFFIX}"
        if existing and os.path.basename(path) in existing and _same_content(path, data):
            yield Generated(index, choices, path, text, sha256(data).hexdigest(), _assignment(fragments, choices),
                            None)
            continue
        writer.write(path, data)
        yield Generated(index, choices, path, text, sha256(data).hexdigest(), _assignment(fragments, choices), None)


def _assignment(fragments: list[list[str]], choices: tuple[int, ...]) -> str:
    return "{" + ", ".join(f[c] for f, c in zip(fragments, choices, strict=True)) + "}"
