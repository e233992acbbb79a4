"""Resolving: a syntax tree (with its imports) → the :mod:`~coverage_engine.resolve.model` the runtime runs.

Entry point: :func:`~coverage_engine.resolve.resolver.resolve`. Names are looked up, types checked,
physical values converted to SI units, defaults, ``keep`` constraints and parameter overrides applied.
"""
