"""The variation generator: one abstract scenario in, every concrete scenario out.

The stages, each a function from one immutable value to the next (:mod:`~coverage_engine.variation.plan`
holds the values):

* *parsed*: :func:`~coverage_engine.variation.plan.parse_variation` finds every ``keep(… in [...])``
  (:mod:`~coverage_engine.variation.dimensions`) and cuts the source text into fixed pieces and value
  slots (:mod:`~coverage_engine.variation.template`);
* *planned*: :mod:`~coverage_engine.variation.design` draws the points of a sampler (their drawn values
  kept in one array, :mod:`~coverage_engine.variation.drawn`) or of an adaptive search, or plans the
  product;
* *checked*: :mod:`~coverage_engine.variation.checking` resolves each value once and reads the keep
  conditions (:mod:`~coverage_engine.variation.conditions`): which combinations no variant may hold;
* *chosen*: :mod:`~coverage_engine.variation.choice` keeps every allowed combination (or a sampler's first
  ``--samples``, or only the new ones), :mod:`~coverage_engine.variation.covering` a t-way covering array
  (:mod:`~coverage_engine.variation.pairwise` and :mod:`~coverage_engine.variation.ipog` build t = 2 fast,
  :mod:`~coverage_engine.variation.covering_size` refuses an array too large before it is built);
* *written*: :mod:`~coverage_engine.variation.output` renders and writes one ``.sce`` per combination
  (:mod:`~coverage_engine.variation.writer` does the file system calls).

:mod:`~coverage_engine.variation.strategies` names the strategies and holds what they share. The design
and the ``.sce`` format are described in ``docs/variation.md``.
"""

from __future__ import annotations

__all__ = ["plan_variation"]


def __getattr__(name: str) -> object:
    if name == "plan_variation":  # imported lazily: the command starts without the resolver
        from coverage_engine.variation.choice import plan_variation

        return plan_variation
    raise AttributeError(name)
