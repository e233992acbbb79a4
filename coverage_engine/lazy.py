"""Per-item values computed when asked for, not stored: what keeps a large drawn sample small.

A sampler drawing 100,000 values for each of 10 continuous ranges makes 1,000,000 choices, each
needed as source text, header comment, stored value, assignment fragment and replacement text. Held
as Python strings that is several hundred megabytes; yet each drawn value is used by exactly one
variant. So the per-choice texts of a drawn dimension are views that format the value when a variant
is rendered: :class:`NumberTexts` (a fixed prefix and suffix around the number, which lets the
renderer spell each number once for all the texts of a row) or :class:`Mapped` (any function);
listed dimensions (a few values, each used by many variants) keep precomputed tuples.
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


class NumberTexts(Mapped[str]):
    """``prefix + spell(number) + suffix`` for each number of ``numbers`` (an ``array('d')``), on access.

    ``spell`` is ``repr`` unless given; a ``spell`` that is not ``repr`` must give ``repr(number)`` for
    every number whose repr is a plain decimal (a dot, no exponent, not inf or nan: written the same
    by ``repr``, JSON and YAML), so a renderer holding the repr may use it: the parts are attributes.
    """

    __slots__ = ("numbers", "prefix", "suffix", "spell")

    def __init__(self, numbers: Sequence[float], prefix: str = "", suffix: str = "",
                 spell: Callable[[float], str] = repr) -> None:
        super().__init__(numbers, lambda number: prefix + spell(number) + suffix)
        self.numbers, self.prefix, self.suffix, self.spell = numbers, prefix, suffix, spell

    def around(self, prefix: str, suffix: str) -> NumberTexts:
        """The same texts with ``prefix`` before and ``suffix`` after each."""
        return NumberTexts(self.numbers, prefix + self.prefix, self.suffix + suffix, self.spell)


def row_texts(slots: Sequence[Sequence[str]], choices: Sequence[int], spelled: Sequence[str | None]) -> list[str]:
    """Each slot's text for its choice in one row; where ``spelled`` holds the number's repr (the slot
    is then a :class:`NumberTexts`), the text is put together from it instead of spelling it again."""
    return [slot[choice] if number is None else slot.prefix + number + slot.suffix  # type: ignore[attr-defined]
            for slot, choice, number in zip(slots, choices, spelled, strict=False)]


def per_choice(values: Sequence[S], fn: Callable[[S], T]) -> Sequence[T]:
    """``fn`` of each value: a lazy view over a long sequence that is itself computed or compact (a
    :class:`Mapped`, an ``array``, a ``range``), a tuple over anything else."""
    if isinstance(values, Mapped):
        return values.then(fn)
    if not isinstance(values, (list, tuple)) and len(values) > LAZY_FROM:
        return Mapped(values, fn)
    return tuple(fn(v) for v in values)
