"""One ``scenario_search`` call as a value, and the part of it a search keeps for ``--resume``.

A search runs for minutes to hours; Ctrl-C and ``--resume`` must continue it exactly as it was started
(the same scenario, goal, seeds and round sizes, and its later rounds' jobs run by the same command with
the same limits), so those settings are written into the search's ``search.json`` before the first
round and read back by ``--resume``. How many jobs run at once (``-j``) is the resuming host's choice.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

from coverage_engine.search.target import SearchTarget
from executor.batch.errors import BatchUsageError

#: The names of the goal options, kept flat in ``search.json``'s settings beside the others.
_TARGET_NAMES = frozenset(field.name for field in fields(SearchTarget))


@dataclass(frozen=True)
class SearchSettings:
    """What decides the variants of every round: kept in ``search.json``, the same after ``--resume``."""

    scenario: str
    goal: str
    budget: int
    round_size: int
    seed: int
    target: SearchTarget = SearchTarget()
    #: How each round's jobs run: the launch command (empty: the built-in runner) and the batch's limits.
    command: tuple[str, ...] = ()
    timeout: float | None = None
    grace: float = 5.0
    retries: int = 0
    simulation: str | None = None

    def document(self) -> dict[str, Any]:
        """The settings as the ``settings`` object of ``search.json`` (the goal options flat among them)."""
        document: dict[str, Any] = {}
        for field in fields(self):
            if field.name == "target":
                document.update(self.target.document())
            else:
                document[field.name] = getattr(self, field.name)
        document["command"] = list(self.command)
        return document

    def setting(self, name: str) -> Any:
        """One setting by its name in ``search.json`` (a goal option's is the target's)."""
        return getattr(self.target, name) if name in _TARGET_NAMES else getattr(self, name)

    @classmethod
    def from_document(cls, document: Mapping[str, Any]) -> SearchSettings | None:
        """The settings kept in a ``search.json`` (None when they are missing or malformed)."""
        known = {f.name for f in fields(cls)} - {"target"}
        values: dict[str, Any] = {k: v for k, v in document.items() if k in known}
        command = values.get("command", [])
        if not isinstance(command, list) or not all(isinstance(part, str) for part in command):
            return None
        values["command"] = tuple(command)
        try:
            settings = cls(**values, target=SearchTarget.from_document(document))
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
    lease: float = 60.0
    store: str | None = None
    resume: bool = False
    wait: bool = False
    debug: bool = False
    #: ``--enqueue-only``: each round's jobs are queued in the shared store for ``scenario_batch_execution
    #: worker`` processes (other hosts); the search runs none and waits for the round to finish.
    enqueue_only: bool = False
    #: With ``--resume``: the settings typed on the command line (the rest come from the search's file).
    typed: tuple[str, ...] = ()


#: The settings ``--resume`` may change: a larger budget continues a search that spent its own.
RESUMABLE_CHANGES = ("budget",)


def resumed(request: SearchRequest, kept: SearchSettings) -> SearchRequest:
    """``request`` with the settings of the search it resumes; a typed setting that differs is refused
    (except the budget), as ``scenario_batch_execution --resume`` refuses options that differ."""
    given = request.settings
    differences = [f"{_flag(name)} {_shown(given.setting(name))} (the search has {_shown(kept.setting(name))})"
                   for name in request.typed
                   if name not in RESUMABLE_CHANGES and given.setting(name) != kept.setting(name)]
    if differences:
        raise BatchUsageError("--resume: the search was started with other settings; it keeps them, so leave "
                              "these out or start a new search in another folder: " + "; ".join(differences))
    settings = replace(kept, budget=given.budget) if "budget" in request.typed else kept
    return replace(request, settings=settings)


def _flag(name: str) -> str:
    return {"scenario": "SCENARIO", "command": "the command", "round_size": "--round"}.get(
        name, "--" + name.replace("_", "-"))


def _shown(value: object) -> str:
    if isinstance(value, tuple):
        return " ".join(value) if value else "none (the built-in runner)"
    return str(value)
