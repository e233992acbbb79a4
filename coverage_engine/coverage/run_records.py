"""What a per-run ``coverage.json`` holds, as frozen records, with the format's constants and bounds.

Schema: ``docs/coverage-json.md``. :mod:`run_schema` checks a decoded document and builds these;
:mod:`run_file` reads, writes and builds files.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from coverage_engine.coverage.values import ValueType
from coverage_engine.results.verdicts import Verdict

FORMAT = "scenario-coverage/run"
FORMAT_VERSION = 1
#: The version of a file that holds ``unsampled`` values (a reader of version 1 would refuse the key, so
#: such a file says it needs a newer reader; every other file stays version 1).
UNSAMPLED_VERSION = 2
#: The versions this release reads.
READABLE_VERSIONS = (FORMAT_VERSION, UNSAMPLED_VERSION)

#: A run's verdicts (the batch's ``timeout`` is an ``error``; a run that did not start is ``skipped``).
VERDICTS = tuple(verdict.value for verdict in Verdict if verdict is not Verdict.PENDING)

#: Item kinds in the file (a cross is a ``cover`` with ``items``).
ITEM_KINDS = ("cover", "record")

#: Bounds: a larger file, more items or more samples is refused with a clear error.
MAX_FILE_BYTES = 32 * 1024 * 1024
MAX_ITEMS = 10_000
MAX_SAMPLES_PER_ITEM = 1_000_000
MAX_NAME_CHARS = 256
MAX_MEMBERS = 10_000
MAX_TEXT_CHARS = 4_096

@dataclass(frozen=True)
class RunInfo:
    """Which run the file belongs to and how it ended."""

    scenario: str
    verdict: str
    source: str | None = None
    variant: str | None = None
    assignment: Mapping[str, object] = field(default_factory=dict)
    reason: str | None = None
    started: str | None = None
    duration: float | None = None


@dataclass(frozen=True)
class ItemDecl:
    """What a cover or record item is: enough to bucket its samples without the ``.osc``."""

    name: str
    kind: str                                   # "cover" | "record"
    path: str = ""                              # scenario / actor path where the item is declared
    value_type: ValueType | None = None         # None for a cross
    unit: str | None = None
    range: tuple[float, float] | None = None
    every: float | None = None
    event: str = "end"
    text: str | None = None
    ignore: str | None = None
    items: tuple[str, ...] = ()                 # a cross: names of cover items of the same path

    @property
    def full_name(self) -> str:
        return f"{self.path}.{self.name}" if self.path else self.name

    @property
    def is_cross(self) -> bool:
        return bool(self.items)

    def signature(self) -> tuple:
        """What must agree between runs for their samples to share buckets."""
        return (self.kind, self.value_type, self.unit, self.range, self.every, self.items)


@dataclass(frozen=True)
class RunCoverage:
    """One run's coverage: the run, its items, and per item the samples and the count ignored at run time."""

    run: RunInfo
    items: tuple[ItemDecl, ...]
    samples: tuple[list, ...]
    ignored: tuple[int, ...]
    #: Per item, the values an ``end`` item had when the run failed (its ``end`` never came): not samples,
    #: but where the failing run was; empty when no item has any.
    unsampled: tuple[list, ...] = ()
