"""The behaviour-tree runtime: build a py_trees tree from the resolved model and tick it.

Modules, by responsibility:

- :mod:`~executor.runtime.pipeline` — what ``scenario_execution`` does, end to end
- :mod:`~executor.runtime.planned_runs` — runs × documents, names, output directories
- :mod:`~executor.runtime.session` — several scenarios in order, simulation life cycle, signals
- :mod:`~executor.runtime.tick_loop` — one scenario: set up, tick loop, result, last snapshot
- :mod:`~executor.runtime.builder` — model → py_trees behaviours, action argument binding
- :mod:`~executor.runtime.directives` / :mod:`~executor.runtime.modifiers` — wait/emit/call, modifiers
- :mod:`~executor.runtime.context` — variables, events, clock of a running scenario

This package's ``__init__`` imports nothing, so light paths (``-n``) stay light.
"""
