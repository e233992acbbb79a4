"""Resolving: a syntax tree (with its imports) → the :mod:`~coverage_engine.resolve.model` the runtime runs.

Entry point: :func:`~coverage_engine.resolve.resolver.resolve`. Names are looked up, types checked,
physical values converted to SI units, defaults, ``keep`` constraints and parameter overrides applied.

``resolver`` runs the passes in order: ``imports`` (files and ``libraries``), ``namespace`` (the
declared ``types``), ``values`` (expressions and instances, by the rules of ``operations``, with
``keeps``), ``do_body`` (behaviours, modifiers), ``coverage_items`` (``cover()``/``record()``),
``checks`` (unused declarations), ``overrides`` (parameter files); ``scope`` is what a pass knows while
it works. Out comes ``model``; ``evaluate`` computes its expressions at run time, ``printer`` shows it.
"""
