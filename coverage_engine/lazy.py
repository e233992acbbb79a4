"""Per-item values computed when asked for, not stored: what keeps a large drawn sample small.

A sampler drawing 100,000 values for each of 10 continuous ranges makes 1,000,000 choices, each
needed as source text, header comment, stored value, assignment fragment and replacement text. Held
as Python strings that is several hundred megabytes; yet each drawn value is used by exactly one
variant. So the per-choice texts of a drawn dimension are :class:`Mapped` views that format the value
when a variant is rendered (:func:`per_choice`); listed dimensions (a few values, each used by many
variants) keep precomputed tuples.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar, overload

T = TypeVar("T")
S = TypeVar("S")

#: Sequences longer than this (and not already lists or tuples) get lazy per-item views.
LAZY_FROM = 64


class Mapped(Sequence[T]):
    """``fn(source[i])`` for each ``i``, computed on every access (nothing is cached)."""

    __slots__ = ("_source", "_fn")

    def __init__(self, source: Sequence[S], fn: Callable[[S], T]) -> None:
        self._source, self._fn = source, fn

    def __len__(self) -> int:
        return len(self._source)

    @overload
    def __getitem__(self, index: int) -> T: ...

    @overload
    def __getitem__(self, index: slice) -> list[T]: ...

    def __getitem__(self, index: Any) -> Any:
        if isinstance(index, slice):
            return [self._fn(item) for item in self._source[index]]
        return self._fn(self._source[index])


    def then(self, fn: Callable[[T], S]) -> Mapped[S]:
        """``fn`` after this view's function, as one view over the same source (one lookup, not two)."""
        first = self._fn
        return Mapped(self._source, lambda item: fn(first(item)))


def per_choice(values: Sequence[S], fn: Callable[[S], T]) -> Sequence[T]:
    """``fn`` of each value: a lazy view over a long sequence that is itself computed or compact (a
    :class:`Mapped`, an ``array``, a ``range``), a tuple over anything else."""
    if isinstance(values, Mapped):
        return values.then(fn)
    if not isinstance(values, (list, tuple)) and len(values) > LAZY_FROM:
        return Mapped(values, fn)
    return tuple(fn(v) for v in values)
