"""Actions: the plugin API (:class:`ActionBase`) and our built-in ``osc.helpers`` actions.

``from executor.actions import ActionBase`` is the import for plugin authors. It is resolved lazily,
so looking up which actions exist (``executor.actions.registry``) does not import py_trees.
"""

from __future__ import annotations

__all__ = ["ActionBase", "ActionError", "VariableHandle"]


def __getattr__(name: str):
    if name in __all__:
        from executor.actions import base

        return getattr(base, name)
    raise AttributeError(f"module 'executor.actions' has no attribute '{name}'")
