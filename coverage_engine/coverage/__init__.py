"""Coverage: from each run's ``coverage.json`` to one graded model, and its renderers.

The flow, one module per step:

``run_records`` / ``run_schema`` / ``run_file``
    the per-run ``coverage.json`` (schema in ``docs/coverage-json.md``): its records, the schema check
    (``json_positions`` points an error at its line and column), a builder the runtime fills, and a
    reader with located errors and bounded sizes; ``values`` the item value types and their checks.
``plan``
    the optional YAML plan: item weights and per-bucket hit targets.
``runs`` / ``results_folder``
    what the merge reads per run (:class:`runs.RunInput`), and a batch's results folder (or one run's
    folder) as a stream of them; verdicts and JUnit come from :mod:`coverage_engine.results`.
``merge``
    folds runs into per-item bucket counts (``buckets`` decides which bucket a value falls in;
    ``input_domains`` gives a varied parameter the buckets its variation declared).
``grading`` / ``model``
    turns the counts and an optional ``plan`` into the :class:`model.CoverageReport`, the one thing every
    renderer reads.
``render_text`` / ``render_json`` / ``render_html`` (with ``render_svg`` and ``report.css``)
    each only renders that one model.

``errors`` holds this package's part of the one exception tree. Nothing here knows about the store or
the runtime: the store's rows reach the merge as the same :class:`runs.RunInput` records
(:mod:`executor.batch.coverage_source` builds them).
"""
