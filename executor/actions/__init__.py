"""Actions: the plugin API (:class:`ActionBase`) and our built-in ``osc.helpers`` actions.

``from executor.actions import ActionBase`` is the import for plugin authors. It is resolved lazily,
so looking up which actions exist (``executor.actions.registry``) does not import py_trees.

``base``
    the plugin API (:class:`ActionBase`, :class:`VariableHandle`).
``registry``
    an action's name to its class: built-ins first, then the ``scenario_execution.actions`` entry points.
``log`` / ``compare`` / ``variables`` / ``run_process`` / ``process_log_check``
    the built-in ``osc.helpers`` actions, one module each (``variables``: increment and decrement).
"""

from __future__ import annotations

__all__ = ["ActionBase", "ActionError", "VariableHandle"]


def __getattr__(name: str) -> object:
    if name in __all__:
        from executor.actions import base

        return getattr(base, name)
    raise AttributeError(f"module 'executor.actions' has no attribute '{name}'")
