"""The action plugin API: :class:`ActionBase` (and the :class:`VariableHandle` it may receive).

An action is a py_trees behaviour with the tutorial's life cycle:

``__init__(self, <some arguments>)``
    configuration; receives the declared arguments it names, with their initial values.
``setup(self, **kwargs)``
    acquire resources once per scenario; ``kwargs`` hold ``logger``, ``input_dir`` (the scenario's
    directory), ``output_dir``, ``clock`` and, in step-based mode, ``simulation``.
``execute(self, <the other arguments>)``
    called each time the action becomes active, with current values (variables read now,
    external methods called now).
``update(self) -> py_trees.common.Status``
    one tick of work; never blocks.
``shutdown(self)``
    clean up at the end of the scenario (stop processes, close files).

Example (see ``examples/example_library``)::

    from executor.actions import ActionBase
    import py_trees

    class CustomAction(ActionBase):
        def execute(self, data: str):
            self.data = data

        def update(self):
            self.logger.info(f"custom action: {self.data}")
            return py_trees.common.Status.SUCCESS

Actions get plain values (``int``, ``float`` in SI units, ``str``, ``bool``, lists, dicts for
structs, ``(name, value)`` tuples for enums). An action that changes variables passes
``resolve_variable_reference_arguments_in_execute=False`` to ``super().__init__`` and then receives a
:class:`VariableHandle` (``get_value``/``set_value``) for each argument
that is a ``var``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import py_trees

from coverage_engine.errors import UserError


class ActionError(UserError):
    """An action cannot do what it was asked (bad argument, missing resource): the scenario fails."""


class ActionBase(py_trees.behaviour.Behaviour):
    """Base class of every action plugin (built-in or from another package)."""

    def __init__(self, resolve_variable_reference_arguments_in_execute: bool = True) -> None:
        super().__init__(type(self).__name__)
        self.resolve_variable_reference_arguments_in_execute = resolve_variable_reference_arguments_in_execute
        #: filled by the runtime: returns the keyword arguments for execute() at activation time
        self._execute_arguments: Callable[[], dict] | None = None

    # -- life cycle hooks for subclasses ---------------------------------------------------------

    def setup(self, **kwargs: Any) -> None:
        """Acquire resources; override as needed (call it with ``**kwargs``; unknown keys are fine)."""

    def shutdown(self) -> None:
        """Clean up at the end of the scenario; override as needed."""

    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.SUCCESS

    # -- runtime plumbing --------------------------------------------------------------------------

    def initialise(self) -> None:
        """Hand the current argument values to ``execute`` each time the action becomes active."""
        execute = getattr(self, "execute", None)
        if execute is not None and self._execute_arguments is not None:
            execute(**self._execute_arguments())


__all__ = ["ActionBase", "ActionError", "VariableHandle"]


class VariableHandle:
    """A writable reference to a ``var``, handed to actions that change variables (``increment``)."""

    __slots__ = ("key", "_store")

    def __init__(self, key: str, store: dict[str, object]) -> None:
        self.key = key
        self._store = store

    def get_value(self) -> object:
        return self._store[self.key]

    def set_value(self, value: object) -> None:
        self._store[self.key] = value

    def __repr__(self) -> str:
        return f"VariableHandle({self.key!r}={self._store.get(self.key)!r})"
