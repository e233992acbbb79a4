"""Coverage: from each run's ``coverage.json`` to one graded model, and its renderers.

The flow, one module per step:

``run_records`` / ``run_schema`` / ``run_file``
    the per-run ``coverage.json`` (schema in ``docs/coverage-json.md``): its records, the schema check,
    and a builder the runtime fills, an atomic writer and a reader with located errors and bounded sizes.
``plan``
    the optional YAML plan: item weights and per-bucket hit targets.
``results_folder``
    a batch's results folder (or one run's folder) as a stream of :class:`runs.RunInput`.
``merge``
    folds runs into per-item bucket counts (``buckets`` decides which bucket a value falls in).
``model``
    the computed report, the one thing every renderer reads.
``grading``
    turns the counts and an optional ``plan`` into the :class:`model.CoverageReport`.
``render_text`` / ``render_json`` / ``render_html``
    each only renders that one model.

Nothing here knows about the store or the runtime: the store's rows reach the merge as the same
:class:`runs.RunInput` records (``executor.batch.coverage_source`` builds them).
"""
