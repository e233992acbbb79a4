"""Bounded YAML: every YAML file we read is limited in size and in what its aliases expand to.

PyYAML shares the node of an alias (``*a``) with its anchor, so a few lines of nested aliases
("billion laughs") load quickly into a small object graph that is exponentially large once anything
walks or copies it as a tree: printing it, merging it into a model, writing it as JSON. A
parameter file of nine such lines grew a run past 3 GB. So before a document is constructed we
count the nodes it stands for with every alias expanded (linear time: a node's expanded size is
computed once) and refuse one that stands for more than :data:`MAX_EXPANDED_NODES`.

Limits (documented in docs/security.md):

- :data:`MAX_YAML_BYTES`: a YAML file we read (parameter file, ``.sce``, coverage plan) is at most
  64 MiB of text;
- :data:`MAX_EXPANDED_NODES`: one document stands for at most a million scalars, sequences and
  mappings once its aliases are expanded;
- :data:`MAX_EXPANDED_BYTES`: and for at most 64 MiB of scalar text (50,000 aliases of one 4 MB
  string pass the node bound and would build 200 GB).

Every loader is :data:`SAFE_LOADER`: libyaml's C loader when PyYAML has it (a 20 MB scalar in a
second instead of a minute).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import yaml

from coverage_engine.limits import MAX_EXPANDED_BYTES, MAX_EXPANDED_NODES, MAX_YAML_BYTES, mib

__all__ = ["MAX_EXPANDED_BYTES", "MAX_EXPANDED_NODES", "MAX_YAML_BYTES", "SAFE_LOADER", "YamlLimitError",
           "check_expansion", "check_size", "compose_bounded", "load_all_bounded", "load_bounded",
           "with_unique_keys", "DuplicateKeyError"]


#: The loader for every YAML we read: libyaml's (about 10x faster on large scalars) where PyYAML was
#: built with it, else the pure-Python one; both only build plain values, and the same bounds apply.
SAFE_LOADER: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class YamlLimitError(ValueError):
    """A YAML text beyond one of the limits; ``line`` and ``column`` are 1-based (0: the whole file)."""

    def __init__(self, message: str, line: int = 0, column: int = 0) -> None:
        super().__init__(message)
        self.line = line
        self.column = column


def check_size(text: str | bytes) -> None:
    """Refuse a text larger than :data:`MAX_YAML_BYTES`."""
    if len(text) > MAX_YAML_BYTES:
        raise YamlLimitError(f"larger than the limit of {mib(MAX_YAML_BYTES)} for a YAML file")


def check_expansion(root: yaml.Node | None) -> None:
    """Refuse a document whose aliases expand to more than :data:`MAX_EXPANDED_NODES` nodes or
    :data:`MAX_EXPANDED_BYTES` bytes of scalar text (50,000 aliases of one 4 MB string are 200 GB)."""
    if root is None:
        return
    sizes: dict[int, tuple[int, int]] = {}          # a node's expanded (nodes, bytes), computed once
    # Iterative post-order walk: a deeply nested document must not exhaust the Python stack either.
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        key = id(node)
        if key in sizes and not children_done:
            continue
        children = _children(node)
        if not children_done:
            sizes.setdefault(key, _ON_PATH)       # on the path: a recursive alias counts once
            stack.append((node, True))
            stack.extend((child, False) for child in children if id(child) not in sizes)
            continue
        nodes, size = 1, len(node.value) if isinstance(node, yaml.ScalarNode) else 0
        for child in children:
            child_nodes, child_bytes = sizes.get(id(child), _ON_PATH)
            nodes, size = nodes + max(child_nodes, 1), size + child_bytes
        if nodes > MAX_EXPANDED_NODES or size > MAX_EXPANDED_BYTES:
            mark = node.start_mark
            what = (f"{MAX_EXPANDED_NODES:,} values" if nodes > MAX_EXPANDED_NODES
                    else f"{mib(MAX_EXPANDED_BYTES)} of text")
            raise YamlLimitError(f"this YAML stands for more than {what} once its aliases (*name) are "
                                 "expanded; refusing it (an alias bomb?)", mark.line + 1, mark.column + 1)
        sizes[key] = (nodes, size)


#: The size recorded for a node whose expansion is being computed (a recursive alias to it counts once).
_ON_PATH = (1, 0)


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [part for pair in node.value for part in pair]
    return []


def load_all_bounded(text: str, loader_class: Any) -> Iterator[Any]:
    """``yaml.load_all`` with the limits: each document is checked before it is constructed."""
    check_size(text)
    loader = loader_class(text)
    try:
        while loader.check_node():
            node = loader.get_node()
            check_expansion(node)
            yield loader.construct_document(node)
    finally:
        loader.dispose()


def load_bounded(text: str, loader_class: Any = SAFE_LOADER) -> Any:
    """``yaml.load`` (one document) with the limits."""
    check_size(text)
    loader = loader_class(text)
    try:
        node = loader.get_single_node()
        check_expansion(node)
        return loader.construct_document(node) if node is not None else None
    finally:
        loader.dispose()


def compose_bounded(text: str, loader_class: Any = SAFE_LOADER) -> yaml.Node | None:
    """``yaml.compose`` (one document) with the limits."""
    check_size(text)
    node = yaml.compose(text, Loader=loader_class)
    check_expansion(node)
    return node


class DuplicateKeyError(YamlLimitError):
    """A key written twice in one mapping (PyYAML alone keeps the last one silently)."""


_UNIQUE_LOADERS: dict[type, type] = {}


def with_unique_keys(loader_class: Any) -> Any:
    """A subclass of ``loader_class`` that refuses a key written twice in one mapping."""
    if loader_class in _UNIQUE_LOADERS:
        return _UNIQUE_LOADERS[loader_class]

    class UniqueKeys(loader_class):
        def construct_mapping(self, node: yaml.Node, deep: bool = False) -> Any:
            if isinstance(node, yaml.MappingNode):
                seen: dict[Any, yaml.Node] = {}
                for key_node, _value in node.value:
                    if key_node.tag == "tag:yaml.org,2002:merge":
                        continue
                    key = self.construct_object(key_node, deep=True)
                    try:
                        first = seen.setdefault(key, key_node)
                    except TypeError:       # an unhashable key: PyYAML reports it
                        continue
                    if first is not key_node:
                        mark = key_node.start_mark
                        raise DuplicateKeyError(f"duplicate key '{key}' (first at line {first.start_mark.line + 1})",
                                                mark.line + 1, mark.column + 1)
            return super().construct_mapping(node, deep=deep)

    _UNIQUE_LOADERS[loader_class] = UniqueKeys
    return UniqueKeys
