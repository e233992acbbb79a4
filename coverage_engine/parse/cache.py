"""Files the front end keeps between runs: parser tables and parsed libraries, in a private folder.

The folder is the user's own cache (``$XDG_CACHE_HOME/scenario-coverage``, else
``~/.cache/scenario-coverage``; ``SCENARIO_CACHE_DIR`` overrides it), created with mode 0700. A cache
holds pickles, and loading a pickle runs code, so nothing is loaded from a place another user could
write: the folder must be a real directory owned by the current user and closed to group and
others, and each file must be a regular file (no symbolic link) owned by the current user and
writable by nobody else. Anything else is ignored, never trusted: the data is rebuilt and, where
the folder is ours, written again.

Every cache file is named by a digest of everything its content depends on (including the source
files that shape it), written atomically, and ignored when it cannot be read, so a stale or broken
cache costs one rebuild, never a wrong result.
"""

from __future__ import annotations

import os
import pickle
import stat
import sys
from pathlib import Path
from typing import TypeVar

K = TypeVar("K")

#: Environment variable naming the cache folder explicitly (tests, read-only homes, CI caches).
CACHE_DIR_VARIABLE = "SCENARIO_CACHE_DIR"

_folder: Path | None = None
_folder_checked = False


def text_digest(text: str) -> str:
    """A 64-bit hex digest for cache file names (zlib's checksums: ``hashlib`` costs ms to import)."""
    import zlib

    data = text.encode()
    return f"{zlib.crc32(data):08x}{zlib.adler32(data):08x}"


def files_digest(folder: Path, names: tuple[str, ...]) -> str:
    """Modification times and sizes of ``names`` under ``folder``, for a cache key (a stat each)."""
    parts = []
    for name in names:
        try:
            info = os.stat(folder / name)
            parts.append(f"{name}:{info.st_mtime_ns}:{info.st_size}")
        except OSError:
            parts.append(f"{name}:missing")
    return "|".join(parts)


def _uid() -> int | None:
    return os.getuid() if hasattr(os, "getuid") else None


def _private(info: os.stat_result) -> bool:
    """Whether a folder or file is the current user's and closed to everybody else's writes."""
    uid = _uid()
    return uid is None or (info.st_uid == uid and not info.st_mode & (stat.S_IWGRP | stat.S_IWOTH))


def cache_folder() -> Path | None:
    """The private cache folder, created if needed; None when no safe one is available."""
    global _folder, _folder_checked
    if _folder_checked:
        return _folder
    _folder_checked = True
    explicit = os.environ.get(CACHE_DIR_VARIABLE)
    if explicit:
        folder = Path(explicit)
    else:
        base = os.environ.get("XDG_CACHE_HOME")
        if not base or not os.path.isabs(base):
            home = os.path.expanduser("~")
            if home == "~" or not os.path.isabs(home):
                return None
            base = os.path.join(home, ".cache")
        folder = Path(base) / "scenario-coverage"
    try:
        os.makedirs(folder, mode=0o700, exist_ok=True)
        info = os.lstat(folder)
    except OSError:
        return None
    if not stat.S_ISDIR(info.st_mode) or not _private(info):
        return None
    uid = _uid()
    if uid is not None and info.st_mode & 0o077:
        try:
            os.chmod(folder, 0o700)       # ours, but readable by others: close it
        except OSError:
            return None
    _folder = folder
    return folder


def cache_file(digest: str, suffix: str = ".pickle") -> Path | None:
    """The cache file for ``digest`` (per Python version) in the private folder, or None without one."""
    folder = cache_folder()
    if folder is None:
        return None
    return folder / f"osc_{digest[:24]}_{sys.version_info[0]}{sys.version_info[1]}{suffix}"


def load(path: Path | None, kind: type[K]) -> K | None:
    """The object pickled at ``path`` if it is a ``kind`` and the file can be trusted, else None."""
    if path is None:
        return None
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError:
        return None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or not _private(info):
            return None
        with os.fdopen(fd, "rb") as handle:
            fd = -1
            loaded = pickle.load(handle)  # noqa: S301 - the user's own private file, checked above
    except (OSError, pickle.PickleError, EOFError, AttributeError, ValueError, TypeError, ImportError,
            IndexError, KeyError, RecursionError, MemoryError):
        return None
    finally:
        if fd >= 0:
            os.close(fd)
    return loaded if isinstance(loaded, kind) else None


def store(path: Path | None, value: object) -> None:
    """Pickle ``value`` to ``path`` atomically; without a usable folder the value is just not kept."""
    if path is None:
        return
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600)
        with os.fdopen(fd, "wb") as handle:
            pickle.dump(value, handle, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
    except OSError:
        try:
            os.unlink(tmp)
        except OSError:
            pass
