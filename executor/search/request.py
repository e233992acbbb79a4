"""One ``scenario_search`` call as a value, and the part of it a search keeps for ``--resume``.

A search runs for minutes to hours; Ctrl-C and ``--resume`` must continue it exactly as it was started
(the same scenario, goal, seeds and round sizes), so those settings are written into the search's
``search.json`` before the first round and read back by ``--resume``. How the jobs run (``-j``,
``--timeout``, the command) is the batch's business: a resumed batch keeps its own.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

from executor.batch.errors import BatchUsageError


@dataclass(frozen=True)
class SearchSettings:
    """What decides the variants of every round: kept in ``search.json``, the same after ``--resume``."""

    scenario: str
    goal: str
    budget: int
    round_size: int
    seed: int
    objective: str | None = None
    maximise: bool = False
    threshold: float | None = None
    resolution: float = 0.01

    def document(self) -> dict[str, Any]:
        """The settings as the ``settings`` object of ``search.json``."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_document(cls, document: Mapping[str, Any]) -> SearchSettings | None:
        """The settings kept in a ``search.json`` (None when they are missing or malformed)."""
        known = {f.name for f in fields(cls)}
        values = {k: v for k, v in document.items() if k in known}
        try:
            settings = cls(**values)
        except TypeError:
            return None
        ok = (isinstance(settings.scenario, str) and isinstance(settings.goal, str)
              and all(isinstance(n, int) and not isinstance(n, bool) and n > 0
                      for n in (settings.budget, settings.round_size))
              and isinstance(settings.seed, int) and not isinstance(settings.seed, bool))
        return settings if ok else None


@dataclass(frozen=True)
class SearchRequest:
    """The command line: the settings, where the search works, and how its jobs run."""

    settings: SearchSettings
    output_dir: str
    slots: int = 1
    timeout: float | None = None
    grace: float = 5.0
    retries: int = 0
    simulation: str | None = None
    lease: float = 60.0
    command: tuple[str, ...] = ()
    store: str | None = None
    resume: bool = False
    wait: bool = False
    debug: bool = False
    #: With ``--resume``: the settings typed on the command line (the rest come from the search's file).
    typed: tuple[str, ...] = ()


#: The settings ``--resume`` may change: a larger budget continues a search that spent its own.
RESUMABLE_CHANGES = ("budget",)


def resumed(request: SearchRequest, kept: SearchSettings) -> SearchRequest:
    """``request`` with the settings of the search it resumes; a typed setting that differs is refused
    (except the budget), as ``scenario_batch_execution --resume`` refuses options that differ."""
    given = request.settings
    differences = [f"--{name.replace('_', '-')} {getattr(given, name)} (the search has {getattr(kept, name)})"
                   for name in request.typed
                   if name not in RESUMABLE_CHANGES and getattr(given, name) != getattr(kept, name)]
    if differences:
        raise BatchUsageError("--resume: the search was started with other settings; it keeps them, so leave "
                              "these out or start a new search in another folder: " + "; ".join(differences))
    settings = replace(kept, budget=given.budget) if "budget" in request.typed else kept
    return replace(request, settings=settings)
