"""The decorator behind syntax and model nodes: typed dataclasses that are cheap to define.

``dataclass(frozen=True)`` generates six methods per class at import time, which made importing the
front end cost more than parsing a file. Nodes are never changed after construction, so :func:`node`
generates only ``__init__`` (with ``__slots__``) and takes equality, hashing and ``repr`` from
:class:`Node`, written once.
"""

from __future__ import annotations

from dataclasses import dataclass


class Node:
    """Value semantics over the dataclass fields, shared by every node class."""

    __slots__ = ()

    def __repr__(self) -> str:
        parts = ", ".join(f"{name}={getattr(self, name)!r}" for name, f in self.__dataclass_fields__.items() if f.repr)
        return f"{type(self).__name__}({parts})"

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(getattr(self, n) == getattr(other, n) for n in self.__dataclass_fields__)

    def __hash__(self) -> int:
        return hash((type(self).__name__, *(getattr(self, n) for n in self.__dataclass_fields__)))


#: Class decorator for node types: a slotted dataclass whose only generated method is ``__init__``.
node = dataclass(slots=True, repr=False, eq=False)
