"""The sizes every input is bounded by, in one place (docs/security.md lists them).

A module with no imports, so that a command's start (which must not import yaml) can read them.
"""

from __future__ import annotations

#: Largest YAML text read (a parameter file, a ``.sce`` file, a coverage plan), in bytes.
MAX_YAML_BYTES = 64 * 1024 * 1024

#: Largest scenario or library file (``.osc``) read, in bytes; a bigger one is refused before it is read.
MAX_SOURCE_BYTES = 64 * 1024 * 1024

#: Most nodes a YAML document may stand for with its aliases expanded.
MAX_EXPANDED_NODES = 1_000_000

#: Most bytes of scalar text a YAML document may stand for with its aliases expanded.
MAX_EXPANDED_BYTES = 64 * 1024 * 1024


def mib(size: int) -> str:
    """``64 MiB``: a limit as messages say it."""
    return f"{size // (1024 * 1024)} MiB"
