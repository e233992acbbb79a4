"""One ``scenario_variation`` call as a value: the file to vary and the command line's options."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from coverage_engine.search import ADAPTIVE
from coverage_engine.search.target import SearchTarget

#: Default of ``--max-variants``: more combinations than this are refused unless the limit is raised.
DEFAULT_MAX_VARIANTS = 10_000_000


@dataclass(frozen=True)
class VariationRequest:
    """One ``scenario_variation`` call: the file to vary and the command line's options."""

    scenario: str
    output_dir: str = "out"
    parameter_file: str | None = None
    list_only: bool = False
    log_model: bool = False
    debug: bool = False
    store: str | None = None
    max_variants: int = DEFAULT_MAX_VARIANTS
    strategy: str = "full"
    strength: int = 2
    samples: int | None = None
    seed: int | None = None
    wait: bool = False
    only_new: bool = False
    #: Results folders of earlier runs an adaptive strategy (boundary, fill-holes, falsify) proposes from.
    from_results: tuple[str, ...] = ()
    #: What the adaptive strategy looks for (``--objective``, ``--threshold``, ``--pass-rate``, …).
    target: SearchTarget = SearchTarget()
    #: The round written in each variant's proposal line; None: one more than the highest round read.
    round_number: int | None = None
    #: Read ``from_results`` from the store (``store``): each names a batch by its output folder.
    from_store: bool = False

    @property
    def adaptive(self) -> bool:
        """Whether the strategy proposes from earlier results (``--from``)."""
        return self.strategy in ADAPTIVE

    def recorded_options(self, source: Path, seed: int | None = None) -> dict[str, object]:
        """The options kept with the run in the store, under the command line's names."""
        return {"output_dir": self.output_dir, "debug": self.debug, "log_model": self.log_model,
                "list": self.list_only, "scenario_parameter_file": self.parameter_file,
                "max_variants": self.max_variants, "source": str(source), "strategy": self.strategy,
                "strength": self.strength, "samples": self.samples, "seed": seed, "only_new": self.only_new,
                **({"from": list(self.from_results), **self.target.document(), "round": self.round_number,
                    "from_store": self.from_store} if self.adaptive else {})}
