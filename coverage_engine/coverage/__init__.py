"""Coverage: from each run's ``coverage.json`` to one graded model, and its renderers.

The flow, one module per step:

``run_file``
    the per-run ``coverage.json`` (schema in ``docs/coverage-json.md``): a builder the runtime fills,
    an atomic writer, and a reader that validates with located errors and bounded sizes.
``results_folder``
    a batch's results folder (or one run's folder) as a stream of :class:`runs.RunInput`.
``merge``
    folds runs into per-item bucket counts (``buckets`` decides which bucket a value falls in).
``grading``
    turns the counts and an optional ``plan`` into the :class:`model.CoverageReport`.
``render_text`` / ``render_json`` / ``render_html``
    each only renders that one model.

Nothing here knows about the store or the runtime: the store's rows reach the merge as the same
:class:`runs.RunInput` records (``executor.coverage_source`` builds them).
"""
