"""What a batch is made of: the scenario files of the input folder, the shard to keep, the launch command.

The launch command is a list of argument templates; ``{SCENARIO}`` and ``{OUTPUT_DIR}`` are replaced
inside each argument and no shell ever reads a value as code (see :mod:`executor.batch.launch_template`).
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from coverage_engine.printable import surrogates_escaped
from coverage_engine.suffixes import SCENARIO_SUFFIXES
from executor.batch.errors import BadCommand, BadShard, CommandNotFound, NoScenarios
from executor.batch.launch_template import OUTPUT_DIR, SCENARIO, Template
from store.jobs import JobSpec

#: File name endings of scenario files (OpenSCENARIO DSL files and the variants written by scenario_variation).

#: Scenario texts up to this size are kept in the store, so workers on other hosts can run them.
MAX_STORED_TEXT = 1024 * 1024


def natural_key(name: str) -> tuple:
    """Sort key that orders the numbers inside names by value: ``cut2`` before ``cut10``."""
    parts = re.split(r"(\d+)", name)
    return tuple((1, int(part), part) if index % 2 else (0, part, "") for index, part in enumerate(parts))


def discover(input_dir: str | os.PathLike[str], *more: str | os.PathLike[str], recursive: bool = False) -> list[Path]:
    """The .sce and .osc files in the input folders, each folder's in natural order of their names (``cut2``
    before ``cut10``), folders in the order given: the order jobs are run and reported in.

    ``recursive`` takes the files of every subfolder too (depth first, natural order). :class:`NoScenarios`
    when a folder is missing or none holds a scenario, or when two files would share a job folder (the
    same stem: a ``.sce`` and an ``.osc``, or one name in two folders).
    """
    files: list[Path] = []
    for given in (input_dir, *more):
        folder = Path(given)
        if not folder.is_dir():
            raise NoScenarios(f"input folder {str(folder)!r} does not exist or is not a folder")
        files += _scenario_files(folder, recursive)
    if not files:
        shown = ", ".join(repr(str(f)) for f in (input_dir, *more))
        raise NoScenarios(f"no .sce or .osc file in {shown}" + ("" if recursive else " (--recursive looks in subfolders)"))
    seen: dict[str, Path] = {}
    for path in files:
        if path.stem in seen:
            raise NoScenarios(f"{path.stem}: {seen[path.stem]} and {path} share a name, their output folders "
                              "would collide")
        seen[path.stem] = path
    return files


def _scenario_files(folder: Path, recursive: bool) -> list[Path]:
    entries = sorted(folder.iterdir(), key=lambda p: natural_key(p.name))
    found = [p for p in entries if p.suffix in SCENARIO_SUFFIXES and p.is_file()]
    if recursive:
        for sub in entries:
            if sub.is_dir() and not sub.is_symlink() and not sub.name.startswith("."):
                found += _scenario_files(sub, True)
    return found


@dataclass(frozen=True)
class Shard:
    """The ``index``-th (1-based) of ``count`` disjoint subsets of the files."""

    index: int
    count: int

    @classmethod
    def parse(cls, text: str) -> Shard:
        try:
            index_text, count_text = text.split("/")
            index, count = int(index_text), int(count_text)
        except ValueError:
            raise BadShard(f"--shard {text!r}: expected i/N, e.g. 2/8") from None
        if count < 1 or not 1 <= index <= count:
            raise BadShard(f"--shard {text!r}: need 1 <= i <= N")
        return cls(index, count)

    def select(self, keys: Sequence[str]) -> set[int]:
        """The positions (in ``keys``) of the files of this shard.

        Files are ordered by their key (content hash, then name), which every host of a CI matrix computes
        alike whatever order its file system lists them in, and dealt round-robin: shards differ in size
        by one file at most (a hash modulo N can leave a shard of 4 files empty).
        """
        order = sorted(range(len(keys)), key=lambda i: keys[i])
        return {position for rank, position in enumerate(order) if rank % self.count == self.index - 1}


def job_specs(files: Sequence[Path], shard: Shard | None = None, *, keep_texts: bool = True) -> list[JobSpec]:
    """One job per file (path made absolute, content hashed), limited to ``shard``.

    ``keep_texts``: the store also keeps each small file's text, for the workers of a shared batch on
    hosts without the file. A local batch runs its files where they are and needs no copy; keeping one
    made every change of a job's row (claimed, started, ended) rewrite the whole text on SQLite, whose
    updates rewrite a row's every page: a third of the batch process's store time on 17 KB variants.
    """
    specs = []
    # A shard hashes every file to place it, holding only the hashes (not 666,469 files' contents).
    kept = shard.select([_content(path, text=False)[0] + "\0" + path.name for path in files]) \
        if shard is not None else None
    real_folders: dict[Path, str] = {}      # each input folder resolved once, not once per file
    for position, path in enumerate(files):
        if kept is not None and position not in kept:
            continue
        sha, text = _content(path, text=keep_texts)
        resolved = _real_path(path, real_folders)
        if not _utf8(resolved):
            # The store (and every report) holds text: a name that is not UTF-8 is kept escaped, so this job
            # alone ends as an error saying so (see not_utf8_reason) and the others run.
            specs.append(JobSpec(name=surrogates_escaped(path.stem), scenario_path=surrogates_escaped(resolved),
                                 scenario_sha=sha))
            continue
        specs.append(JobSpec(name=path.stem, scenario_path=resolved, scenario_sha=sha,
                             scenario_text=text))
    return specs


def _content(path: Path, *, text: bool = True) -> tuple[str, str | None]:
    """The file's SHA-256 and, when it is small UTF-8 text without NUL (and ``text`` asks for it), the text
    itself. A large file is hashed in chunks, never held whole (a stray 500 MB file costs a 1 MiB
    buffer, not 500 MB). Without ``text`` the bytes are not decoded: a local batch keeps no text, and
    decoding was a fifth of enqueueing 2,000 variants of 17 KB."""
    with open(path, "rb") as handle:
        # a buffer the file's size (a byte more, to see its end), not MAX_STORED_TEXT for each file:
        # a megabyte mapped, touched and shrunk per file cost more than reading a small one
        asked = min(os.fstat(handle.fileno()).st_size, MAX_STORED_TEXT) + 1
        head = handle.read(asked)
        digest = hashlib.sha256(head)
        kept: bytes | None = head if text and len(head) <= MAX_STORED_TEXT else None  # at most this much is held
        if len(head) == asked:         # not at its end yet: a large file, or one that grew since fstat
            for chunk in iter(lambda: handle.read(MAX_STORED_TEXT), b""):
                digest.update(chunk)
                kept = kept + chunk if kept is not None and len(kept) + len(chunk) <= MAX_STORED_TEXT else None
    if kept is None:
        return digest.hexdigest(), None
    try:
        decoded = kept.decode("utf-8")
    except UnicodeDecodeError:
        return digest.hexdigest(), None
    return digest.hexdigest(), None if "\x00" in decoded else decoded


def _real_path(path: Path, real_folders: dict[Path, str]) -> str:
    """``path.resolve()``, with the folder's real path looked up once (a file that is a link is resolved)."""
    if path.is_symlink():
        return str(path.resolve())
    folder = path.parent
    real = real_folders.get(folder)
    if real is None:
        real = real_folders[folder] = str(folder.resolve())
    return os.path.join(real, path.name)


def not_utf8(files: Sequence[Path]) -> list[str]:
    """The files whose names are not UTF-8, escaped for printing (their jobs will fail: rename them)."""
    return [surrogates_escaped(str(p)) for p in files if not _utf8(str(p))]


_ESCAPED_BYTE = re.compile(r"\\x([89a-f][0-9a-f])")


def not_utf8_reason(scenario_path: str) -> str | None:
    """Why a job cannot run when its recorded path is a name that is not UTF-8, kept escaped (``c\\xff.osc``):
    the escaped path does not exist and the file of the raw bytes does. None for every other path."""
    if not _ESCAPED_BYTE.search(scenario_path) or os.path.lexists(scenario_path):
        return None
    raw = _ESCAPED_BYTE.sub(lambda m: chr(0xDC00 + int(m.group(1), 16)), scenario_path)
    if not os.path.lexists(raw):
        return None
    return (f"the file name {scenario_path} is not UTF-8 (shown escaped); the store and the reports hold text: "
            f"rename the file")


def _utf8(text: str) -> bool:
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True




def check_command(command: Sequence[str], *, require_executable: bool = True) -> tuple[str, ...]:
    """Validate the launch command: non-empty, with both placeholders, its program found on PATH."""
    if not command:
        raise BadCommand("no launch command given; put it after --, e.g. "
                         "-- scenario_execution {SCENARIO} --output-dir {OUTPUT_DIR}")
    missing = [p for p in (SCENARIO, OUTPUT_DIR) if not any(p in arg for arg in command)]
    if missing:
        raise BadCommand(f"the launch command must contain {' and '.join(missing)} "
                         f"(got: {' '.join(command)})")
    Template.of(command)                      # refuses a placeholder that a shell could read as code
    program = command[0]
    if require_executable and SCENARIO not in program and OUTPUT_DIR not in program:
        if shutil.which(program) is None:
            raise CommandNotFound(f"launch command not found: {program}")
    return tuple(command)
