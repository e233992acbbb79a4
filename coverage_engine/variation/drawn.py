"""The values a sampler drew for a continuous range: one ``array('d')``, choices made on access.

See :mod:`coverage_engine.lazy` for why nothing per drawn value is held beyond its number.
"""

from __future__ import annotations

from array import array
from collections.abc import Sequence
from typing import Any, overload

from coverage_engine.lazy import Mapped
from coverage_engine.variation.dimensions import Choice, RangeSpec


class DrawnChoices(Sequence[Choice]):
    """The values drawn for a continuous range, as :class:`Choice` objects made on access."""

    __slots__ = ("values", "spec")

    def __init__(self, values: array, spec: RangeSpec) -> None:
        self.values, self.spec = values, spec

    def __len__(self) -> int:
        return len(self.values)

    @overload
    def __getitem__(self, index: int) -> Choice: ...

    @overload
    def __getitem__(self, index: slice) -> list[Choice]: ...

    def __getitem__(self, index: Any) -> Any:
        if isinstance(index, slice):
            return [self._choice(v) for v in self.values[index]]
        return self._choice(self.values[index])

    def _choice(self, value: float) -> Choice:
        return Choice(self.spec.text(value), value, self.spec.location)

    @property
    def texts(self) -> Mapped[str]:
        """Each drawn value as source text (``12.5kph``)."""
        return Mapped(self.values, self.spec.text)
