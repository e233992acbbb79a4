"""Everything that runs: scenarios, their variants, batches of them. Imports ``coverage_engine`` and ``store``,
never ``cli`` (the fork server finds the command's entry point through its console script).

``runtime/``
    ``scenario_execution``: the model becomes a py_trees tree that is ticked on the wall clock or a
    simulation's steps (``simulation``); its verdicts and samples become ``test.xml`` and ``coverage.json``.
``actions/``
    the action plugin API and the built-in ``osc.helpers`` actions.
``simulations/``
    the simulation libraries (``osc.pybullet``, ``osc.ros``, ``osc.nav2``, ``osc.gazebo``), each an extra.
``variation/``
    ``scenario_variation``: runs the language's variation stages and records the variants in the store.
``batch/``
    ``scenario_batch_execution``: jobs in the store's queue, workers that run them (forked or launched),
    their verdicts, the merged report, the runs a coverage report reads from the store.
``children/``
    one child process in its own process group, and the ``--post-run`` hooks (runtime and batch).
``output/``
    the output folder's lock and the terminal policy (variation and batch).

The results they write (JUnit document, names, reader, verdicts, atomic writer) live in
:mod:`coverage_engine.results`, where the coverage model reads them too. This ``__init__`` imports nothing.
"""
