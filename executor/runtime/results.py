"""The outcome of one executed scenario, as written to ``test.xml``."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class ScenarioResult:
    """``passed`` or not; on failure a one-line ``message`` and ``output`` (the last tree snapshot)."""

    name: str
    passed: bool
    message: str = ""
    output: str = ""
    duration: float = 0.0
    start_time: float = 0.0
    output_dir: str | None = None
    aborted: bool = False
