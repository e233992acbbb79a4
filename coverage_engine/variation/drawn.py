"""The values a sampler drew for a continuous range: one ``array('d')``, choices made on access.

See :mod:`coverage_engine.lazy` for why nothing per drawn value is held beyond its number.
"""

from __future__ import annotations

from array import array

from coverage_engine.lazy import Mapped, NumberTexts
from coverage_engine.variation.dimensions import Choice, RangeSpec


class DrawnChoices(Mapped[Choice]):
    """The values drawn for a continuous range, as :class:`Choice` objects made on access."""

    __slots__ = ("values", "spec")

    def __init__(self, values: array, spec: RangeSpec) -> None:
        super().__init__(values, lambda value: Choice(spec.text(value), value, spec.location))
        self.values, self.spec = values, spec

    @property
    def texts(self) -> NumberTexts:
        """Each drawn value as source text (``12.5kph``, as :meth:`RangeSpec.text` spells it)."""
        return NumberTexts(self.values, "", self.spec.unit)
