"""Value types of coverage items and the checks a sample must pass.

A sample is a JSON scalar: ``int`` and ``float`` items take numbers (an ``int`` item only integers),
``bool`` items ``true``/``false``, ``string`` items text, and ``enum`` items the name of one of their
members. Non-finite numbers are never samples (JSON cannot hold them; the builder counts them as
ignored instead).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: The kinds of value an item may have.
KINDS = ("int", "float", "bool", "string", "enum")

#: Kinds whose samples are numbers (bucketed by range, or one bucket per distinct value).
NUMERIC = ("int", "float")


@dataclass(frozen=True)
class ValueType:
    """The type of an item's values; ``members`` lists an enum's member names in declaration order."""

    kind: str
    members: tuple[str, ...] = ()

    @property
    def numeric(self) -> bool:
        return self.kind in NUMERIC

    def accepts(self, value: object) -> bool:
        """Whether ``value`` (as decoded from JSON) is a valid sample of this type."""
        kind = self.kind
        if kind == "float":
            return (type(value) is float or type(value) is int) and math.isfinite(value)
        if kind == "int":
            return type(value) is int
        if kind == "bool":
            return type(value) is bool
        if kind == "string":
            return type(value) is str
        return type(value) is str and value in self.members

    def describe(self) -> str:
        """``float``, ``enum [left, right]`` …, for reports."""
        if self.kind == "enum":
            return "enum [" + ", ".join(self.members) + "]"
        return self.kind


BOOL = ValueType("bool")
