"""Simulated nodes and their parameters, the target of ``set_node_parameter``.

A ROS node declares typed parameters and accepts or refuses each update. The simulated system
has a few such nodes (the laser's ``laserscan_modification``, the navigation's
``controller_server``); :meth:`NodeGraph.set` converts the text value of ``set_node_parameter`` to
the parameter's type, checks it, and hands it to the node, or raises :class:`ParameterError`
saying why not.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass


class ParameterError(ValueError):
    """The node or parameter does not exist, or the value is refused."""


@dataclass
class Parameter:
    """A typed parameter with its current value; ``check`` returns a reason to refuse a value, or None."""

    kind: type
    value: object
    description: str
    check: Callable[[object], str | None] | None = None


class ParameterNode:
    """A named node; ``on_change(name, value)`` applies an accepted value."""

    def __init__(self, name: str, parameters: dict[str, Parameter],
                 on_change: Callable[[str, object], None]) -> None:
        self.name = name
        self.parameters = parameters
        self.on_change = on_change


class NodeGraph:
    """The simulated nodes by name."""

    def __init__(self) -> None:
        self.nodes: dict[str, ParameterNode] = {}

    def add(self, node: ParameterNode) -> None:
        self.nodes[node.name] = node

    def set(self, node_name: str, parameter_name: str, text: str) -> object:
        """Set ``node_name``'s ``parameter_name`` from its text form; returns the typed value."""
        node = self.nodes.get(node_name.lstrip("/"))
        if node is None:
            known = ", ".join(sorted(self.nodes)) or "none"
            raise ParameterError(f"no node '{node_name}' in the simulated system (nodes: {known}); "
                                 "other nodes need ROS")
        parameter = node.parameters.get(parameter_name)
        if parameter is None:
            known = ", ".join(sorted(node.parameters))
            raise ParameterError(f"node '{node.name}' has no parameter '{parameter_name}' (parameters: {known})")
        value = _convert(text, parameter.kind, f"{node.name}.{parameter_name}")
        reason = parameter.check(value) if parameter.check else None
        if reason:
            raise ParameterError(f"{node.name} refused {parameter_name} = {text!r}: {reason}")
        parameter.value = value
        node.on_change(parameter_name, value)
        return value


def _convert(text: object, kind: type, where: str) -> object:
    raw = str(text).strip()
    try:
        if kind is bool:
            if raw.lower() not in ("true", "false"):
                raise ValueError(raw)
            return raw.lower() == "true"
        if kind is int:
            return int(raw)
        if kind is float:
            value = float(raw)
            if not math.isfinite(value):
                raise ValueError(raw)
            return value
        return raw
    except ValueError:
        raise ParameterError(f"{where} is a {kind.__name__} parameter: {text!r} is not one") from None


def within(low: float, high: float) -> Callable[[object], str | None]:
    """A check refusing numbers outside ``[low, high]``."""
    def check(value: object) -> str | None:
        return None if isinstance(value, (int, float)) and low <= value <= high else f"must be within [{low:g}, {high:g}]"
    return check


def at_least(low: float) -> Callable[[object], str | None]:
    """A check refusing numbers below ``low``."""
    def check(value: object) -> str | None:
        return None if isinstance(value, (int, float)) and value >= low else f"must be at least {low:g}"
    return check
