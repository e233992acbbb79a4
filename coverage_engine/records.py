"""The decorator behind syntax nodes and model records: small immutable records that are cheap to define.

``dataclasses.dataclass(frozen=True)`` made importing the front end cost more than parsing a file
(each class takes a fraction of a millisecond to process, and ``scenario_execution -n`` has a budget
of a few tens of milliseconds). :func:`record` reads the annotated fields in order, gives the class
``__slots__`` and one generated ``__init__``, and takes immutability, equality, hashing and ``repr``
from :class:`Record`, written once. To type checkers the decorator says "a frozen dataclass"
(``typing.dataclass_transform``), so they know each record's constructor and fields.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING or sys.version_info >= (3, 11):
    from typing import dataclass_transform
else:  # Python 3.10: the marker only informs type checkers, so nothing is lost without it
    def dataclass_transform(**_kwargs):
        return lambda decorator: decorator

_set = object.__setattr__


class Record:
    """Value semantics over the record's fields; assigning to a field after construction is an error."""

    __slots__ = ()
    _fields: tuple[str, ...] = ()
    _hidden_in_repr: tuple[str, ...] = ()

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable (use records.replace)")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __repr__(self) -> str:
        parts = ", ".join(f"{n}={getattr(self, n)!r}" for n in self._fields if n not in self._hidden_in_repr)
        return f"{type(self).__name__}({parts})"

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(getattr(self, n) == getattr(other, n) for n in self._fields)

    def __hash__(self) -> int:
        return hash((type(self).__name__, *(getattr(self, n) for n in self._fields)))

    def __reduce__(self) -> tuple[type[Record], tuple[object, ...]]:
        return (type(self), tuple(getattr(self, n) for n in self._fields))


R = TypeVar("R", bound=Record)


@dataclass_transform(eq_default=True, frozen_default=True)
def record(cls: type[R]) -> type[R]:
    """Turn an annotated class deriving from :class:`Record` into a slotted record with those fields.

    Fields are the class's own annotations in order; a class attribute of the same name is the
    field's default. Methods and properties of the class are kept.
    """
    own = cls.__dict__
    names = tuple(own.get("__annotations__", {}))
    defaults = {n: own[n] for n in names if n in own}
    body = {k: v for k, v in own.items() if k not in names and k not in ("__dict__", "__weakref__")}
    body["__slots__"] = names
    body["_fields"] = names
    params = ", ".join(f"{n}=_default_{n}" if n in defaults else n for n in names)
    lines = [f"def __init__(self, {params}):"] + [f"    _set(self, {n!r}, {n})" for n in names]
    namespace = {"_set": _set, **{f"_default_{n}": v for n, v in defaults.items()}}
    exec(compile("\n".join(lines) or "pass", f"<record {cls.__name__}>", "exec"), namespace)  # noqa: S102
    body["__init__"] = namespace["__init__"]
    new = type(cls.__name__, cls.__bases__, body)
    new.__qualname__ = cls.__qualname__
    return new


def replace(record: R, **changes: object) -> R:
    """A copy of ``record`` with some fields changed."""
    values = {n: getattr(record, n) for n in record._fields}
    values.update(changes)
    return type(record)(**values)
