"""The axes of a variation as a unit cube: where a run's assigned value sits, and which value a point picks.

An axis is what the variation declared for one varied parameter (:class:`~coverage_engine.domains.InputDomain`):
a continuous range maps a coordinate ``u`` in [0, 1] to ``low + u * (high - low)``; a listed axis of ``k``
values maps ``u`` to value index ``min(floor(u * k), k - 1)``, so the centre of value ``i`` is
``(i + 0.5) / k``. The variation's ``design_points`` applies the same rule to every strategy's points,
so a proposal made here lands on the variant it names.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from coverage_engine.domains import InputDomain, numeric_value

#: A point of the unit cube, one coordinate per axis.
Point = tuple[float, ...]


@dataclass(frozen=True)
class Space:
    """The axes of one variation, in the variation's order."""

    axes: tuple[InputDomain, ...]

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(axis.key for axis in self.axes)

    @property
    def continuous(self) -> tuple[bool, ...]:
        """Per axis, whether it is a continuous range (a sampler draws any value in it)."""
        return tuple(axis.values is None for axis in self.axes)

    def levels(self, axis: int) -> int | None:
        """How many values a listed axis has (None for a continuous one)."""
        values = self.axes[axis].values
        return None if values is None else len(values)

    def point_of(self, assignment: Mapping[str, object]) -> Point | None:
        """Where a run with ``assignment`` sits, or None when a value is missing or outside its axis."""
        point = []
        for axis in self.axes:
            if axis.key not in assignment:
                return None
            coordinate = coordinate_of(axis, assignment[axis.key])
            if coordinate is None:
                return None
            point.append(coordinate)
        return tuple(point)

    def value_at(self, axis: int, u: float) -> object:
        """The value a coordinate picks on ``axis`` (a number in the range's unit, or a listed value)."""
        domain = self.axes[axis]
        if domain.values is not None:
            k = len(domain.values)
            return domain.values[min(int(u * k), k - 1)]
        assert domain.low is not None and domain.high is not None
        return domain.low + u * (domain.high - domain.low)

    def snap(self, point: Sequence[float]) -> Point:
        """``point`` clipped to the cube, a listed axis's coordinate moved to the centre of its value."""
        out = []
        for axis, u in enumerate(point):
            u = min(1.0, max(0.0, u))
            k = self.levels(axis)
            if k is not None:
                u = (min(int(u * k), k - 1) + 0.5) / k
            out.append(u)
        return tuple(out)


def coordinate_of(axis: InputDomain, value: object) -> float | None:
    """The unit coordinate of a stored ``value`` on ``axis`` (the centre of a listed value's cell)."""
    if axis.values is not None:
        for index, known in enumerate(axis.values):
            if known == value and type(known) is type(value):
                return (index + 0.5) / len(axis.values)
        number = numeric_value(value)
        if number is not None:        # 30kph stored as "30kph" in one file and 30 in another
            for index, known in enumerate(axis.values):
                if numeric_value(known) == number:
                    return (index + 0.5) / len(axis.values)
        return None
    number = numeric_value(value)
    if number is None or axis.low is None or axis.high is None:
        return None
    span = axis.high - axis.low
    if span <= 0:
        return 0.5
    u = (number - axis.low) / span
    slack = 1e-9
    return min(1.0, max(0.0, u)) if -slack <= u <= 1 + slack else None


def chebyshev(a: Sequence[float], b: Sequence[float]) -> float:
    """The largest difference of two points along any axis (fractions of each range)."""
    return max((abs(x - y) for x, y in zip(a, b, strict=True)), default=0.0)


def euclidean(a: Sequence[float], b: Sequence[float]) -> float:
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b, strict=True)))
