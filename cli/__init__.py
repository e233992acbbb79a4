"""The four commands and the pytest plugin: click options in, calls into the packages, messages and exit codes out.

``scenario_execution`` / ``scenario_variation`` / ``scenario_batch_execution`` / ``scenario_coverage``
    one module per command: parse options, call :mod:`executor` (and :mod:`coverage_engine`), nothing else.
``options``
    the options several commands share (``--store``, ``-d/--debug``, seconds), defined once.
``boundary``
    the one place exceptions become a located message on stderr and an exit code.
``pytest_plugin``
    ``pytest --osc PATH``: scenarios and variants as test items, each run through ``scenario_execution``.

Nothing else imports this package (the fork server finds the command through its console script).
"""
