"""The variation generator: one abstract scenario in, every concrete scenario out.

Passes, in order (each its own module):

* :mod:`~coverage_engine.variation.dimensions` finds every ``keep(… in [...])`` in the syntax tree;
* :mod:`~coverage_engine.variation.template` cuts the source text into fixed pieces and value slots;
* :mod:`~coverage_engine.variation.plan` checks each value once and streams the valid combinations;
* :mod:`~coverage_engine.variation.conditions` turns the keeps that are neither a value nor a list into
  constraints: which combinations no variant may hold;
* :mod:`~coverage_engine.variation.strategies` chooses the combinations: the full product, a t-way
  covering array (:mod:`~coverage_engine.variation.pairwise` builds t = 2 fast) or a seeded sample, whose
  drawn values :mod:`~coverage_engine.variation.drawn` keeps in one array;
* :mod:`~coverage_engine.variation.output` renders and writes one ``.sce`` per combination
  (:mod:`~coverage_engine.variation.writer` does the file system calls).

The design and the ``.sce`` format are described in ``docs/variation.md``.
"""

from __future__ import annotations

__all__ = ["plan_variation"]


def __getattr__(name: str):
    if name == "plan_variation":  # imported lazily: the command starts without the resolver
        from coverage_engine.variation.plan import plan_variation

        return plan_variation
    raise AttributeError(name)
