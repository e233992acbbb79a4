"""``scenario_variation``'s orchestration: run the variation generator of ``coverage_engine`` and record its output.

:mod:`~executor.variation.generation` takes a :class:`~executor.variation.generation.VariationRequest`
(plan → check → report → write ``.sce`` files → record them in the store, stoppable by signals);
:mod:`~executor.variation.report` is what people read meanwhile. The language side (dimensions,
value checks, the ``.sce`` format) stays in :mod:`coverage_engine.variation`.
"""
