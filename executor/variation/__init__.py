"""``scenario_variation``'s orchestration: run the variation stages of ``coverage_engine`` and record their output.

* :mod:`~executor.variation.request`: one call as a value (:class:`~executor.variation.request.VariationRequest`);
* :mod:`~executor.variation.generation`: runs the stages in order (parse → design → check → choose), then
  hands the chosen plan to
* :mod:`~executor.variation.writing`: writes the ``.sce`` files and records them in the store, stoppable by
  signals without losing a written file's row;
* :mod:`~executor.variation.report`: what people read meanwhile.

The language side (dimensions, value checks, the ``.sce`` format) stays in :mod:`coverage_engine.variation`.
"""
