"""Files the front end keeps between runs in the temporary folder: parser tables and parsed libraries.

Every cache file is named by a digest of everything its content depends on, written atomically,
and ignored when it cannot be read, so a stale or broken cache costs one rebuild, never a wrong
result.
"""

from __future__ import annotations

import os
import pickle
import sys
from pathlib import Path
from typing import TypeVar

K = TypeVar("K")


def text_digest(text: str) -> str:
    """A 64-bit hex digest for cache file names (zlib's checksums: ``hashlib`` costs ms to import)."""
    import zlib

    data = text.encode()
    return f"{zlib.crc32(data):08x}{zlib.adler32(data):08x}"


def cache_file(digest: str, suffix: str = ".pickle") -> Path:
    """The cache file for ``digest``, per user and Python version, in the temporary folder."""
    user = os.environ.get("USER") or str(os.getuid() if hasattr(os, "getuid") else "user")
    name = f".osc_lalr_{user}_{digest[:20]}_{sys.version_info[0]}{sys.version_info[1]}{suffix}"
    base = os.environ.get("TMPDIR") or ("/tmp" if os.name == "posix" else None)
    if base is None:  # tempfile costs a few ms to import; only where /tmp does not exist
        import tempfile

        base = tempfile.gettempdir()
    return Path(base) / name


def load(path: Path, kind: type[K]) -> K | None:
    """The object pickled at ``path`` if it is a ``kind``, else None (missing, unreadable or stale)."""
    try:
        with open(path, "rb") as handle:
            loaded = pickle.load(handle)
    except (OSError, pickle.PickleError, EOFError, AttributeError, ValueError, TypeError, ImportError):
        return None
    return loaded if isinstance(loaded, kind) else None


def store(path: Path, value: object) -> None:
    """Pickle ``value`` to ``path`` atomically; without a writable folder the value is just not kept."""
    try:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        with open(tmp, "wb") as handle:
            pickle.dump(value, handle, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
    except OSError:
        pass
