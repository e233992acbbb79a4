"""The behaviour-tree runtime: build a py_trees tree from the resolved model and tick it.

Modules, by responsibility:

- :mod:`~executor.runtime.pipeline` — what ``scenario_execution`` does, end to end
- :mod:`~executor.runtime.planned_runs` — runs × documents, names, output directories
- :mod:`~executor.runtime.session` — several scenarios in order, simulation life cycle, signals
- :mod:`~executor.runtime.tick_loop` — one scenario: set up, tick loop, result, last snapshot
- :mod:`~executor.runtime.builder` — model → py_trees behaviours, action argument binding
- :mod:`~executor.runtime.directives` / :mod:`~executor.runtime.modifiers` — wait/emit/call, modifiers
- :mod:`~executor.runtime.context` — variables, events, clock of a running scenario
- :mod:`~executor.runtime.simulation` — the wall and simulation clocks, the step-based simulation interface
- :mod:`~executor.runtime.quiescence` — the earliest time a tick could change anything (ticks skipped until then)
- :mod:`~executor.runtime.coverage_sampling` — ``cover()``/``record()`` samples and the run's ``coverage.json``
- :mod:`~executor.runtime.recording` / :mod:`~executor.runtime.live` / :mod:`~executor.runtime.dot` /
  :mod:`~executor.runtime.logger` — ``--bt-log``/``--tick-log``, ``--live-tree``, ``--dot``, the line logger
- :mod:`~executor.runtime.external_methods` — the Python side of ``osc.helpers``' external methods
- :mod:`~executor.runtime.parameter_locations` — a parameter-file error pointed at its key

This package's ``__init__`` imports nothing, so light paths (``-n``) stay light.
"""
