"""Which bucket a sampled value falls in, and the buckets an item has.

Four kinds of bucketing, chosen from an item's declaration:

* **range** — a numeric item with ``range: [a..b]``: equal-width buckets of ``every`` (in the item's
  unit). A ``float`` bucket is half open, ``[a..a+every)``, the last one closed at ``b``; an ``int``
  bucket holds ``every`` whole numbers (``every`` must be whole). Without ``every`` an ``int`` range of at
  most 20 values has one bucket per value, any other range ten buckets. A value outside the range
  falls in no bucket: it is counted as *ignored*, not lost.
* **members** — ``enum`` and ``bool`` items: one bucket per member; every member is part of the goal.
* **distinct** — numbers without a range and strings: one bucket per distinct value seen (at most
  :data:`DISTINCT_LIMIT`; later new values are ignored and the report says so). Varied parameters
  (input coverage, :mod:`~coverage_engine.coverage.input_domains`) use its keys, bucketed by what the
  variation declared.
* **cross** — a tuple of component keys; the buckets are the product of the components' buckets.

A *key* is what the merge counts under while runs stream in (a bucket index, a member name, a value,
a tuple); :meth:`finish` maps the keys seen to the final, ordered list of :class:`Bucket`. ``keys``
computes the keys of a whole column of values at once, with C-level ``map`` where it can (the merge
calls it once per item and chunk of runs, not once per sample).
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Sequence
from dataclasses import dataclass
from itertools import repeat
from operator import floordiv, sub

from coverage_engine.coverage.values import ValueType

#: Most buckets one range may have (``every`` too small is an error).
MAX_BUCKETS = 10_000

#: Most distinct values an item without a range gets buckets for.
DISTINCT_LIMIT = 1_000

#: Up to this many whole numbers, an ``int`` range without ``every`` has one bucket per value.
_INT_VALUES_PER_BUCKET_LIMIT = 20
_DEFAULT_BINS = 10


def format_number(value: float | int) -> str:
    """A short, exact spelling of a number for labels (``10``, ``2.5``, ``0.1``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    text = f"{value:.6g}"
    return text if float(text) == value else repr(value)


def value_label(value: object) -> str:
    """How a sampled or assigned value is shown."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return format_number(value)
    return str(value)


@dataclass(frozen=True)
class Bucket:
    """One bucket: its label and, for numeric buckets, its bounds (``high`` is inclusive for the last)."""

    label: str
    low: float | None = None
    high: float | None = None
    value: object = None


def default_every(kind: str, low: float, high: float) -> float:
    """The bucket width of a range declared without ``every``."""
    if kind == "int":
        count = int(high) - int(low) + 1
        return 1 if count <= _INT_VALUES_PER_BUCKET_LIMIT else math.ceil(count / _DEFAULT_BINS)
    return (high - low) / _DEFAULT_BINS if high > low else 1.0


def range_bucket_count(kind: str, low: float, high: float, every: float) -> int:
    """How many buckets ``range: [low..high], every: every`` makes for an item of ``kind``."""
    if kind == "int":
        return max(1, math.ceil((int(high) - int(low) + 1) / every))
    if high == low:
        return 1
    return max(1, math.ceil((high - low) / every - 1e-9))


class RangeBuckets:
    """Equal-width buckets over ``[low..high]``; the key of a value is its bucket's index."""

    kind = "range"

    def __init__(self, value_kind: str, low: float, high: float, every: float | None) -> None:
        self.integer = value_kind == "int"
        self.low, self.high = low, high
        self.every = every if every is not None else default_every(value_kind, low, high)
        self.count = range_bucket_count(value_kind, low, high, self.every)
        # Whether the buckets end exactly at ``high`` (then only ``high`` itself needs a second look).
        span = (int(high) - int(low) + 1) if self.integer else (high - low)
        self._aligned = span == self.count * self.every

    def key(self, value: object) -> int | None:
        if not isinstance(value, (int, float)) or value < self.low or value > self.high:
            return None
        return self.index(value)

    def index(self, value: float) -> int:
        """The bucket of a value known to lie in the range."""
        index = int((value - self.low) // self.every)
        return index if index < self.count else self.count - 1

    def keys(self, values: list) -> list:
        raw = list(map(floordiv, map(sub, values, repeat(self.low)), repeat(self.every)))
        last = self.count - 1
        if raw and min(raw) >= 0 and max(raw) < (self.count if self._aligned else last):
            return raw
        key = self.key   # below the range, or in the last bucket (which may end before a full width)
        return [i if 0 <= i < last else key(v) for v, i in zip(values, raw, strict=True)]

    def buckets(self) -> list[Bucket]:
        out = []
        for i in range(self.count):
            start = self.low + i * self.every
            if self.integer:
                end = min(start + self.every - 1, self.high)
                label = format_number(start) if end == start else f"{format_number(start)}..{format_number(end)}"
            else:
                end = self.high if i == self.count - 1 else start + self.every
                closing = "]" if i == self.count - 1 else ")"
                label = f"[{format_number(start)}..{format_number(end)}{closing}"
            out.append(Bucket(label, low=start, high=end))
        return out

    def finish(self, keys: Iterable[Hashable]) -> tuple[list[Bucket], dict[Hashable, int]]:
        return self.buckets(), {i: i for i in range(self.count)}


class MemberBuckets:
    """One bucket per enum member (or ``false``/``true``); the key is the member itself."""

    kind = "members"

    def __init__(self, members: Sequence[object]) -> None:
        self.members = tuple(members)
        self._index = {m: i for i, m in enumerate(self.members)}
        self._same = {m: m for m in self.members}

    def key(self, value: object) -> object | None:
        return value if value in self._index and type(value) is type(self.members[0]) else None

    def keys(self, values: list) -> list:
        return list(map(self._same.get, values))   # samples were checked against the type when read

    def finish(self, keys: Iterable[Hashable]) -> tuple[list[Bucket], dict[Hashable, int]]:
        return [Bucket(value_label(m), value=m) for m in self.members], dict(self._index)


def _numbers(keys: Sequence[Hashable]) -> list[int | float] | None:
    """The keys ascending when every one is a number (not a bool), else None."""
    numbers = [k for k in keys if isinstance(k, (int, float)) and not isinstance(k, bool)]
    return sorted(numbers) if numbers and len(numbers) == len(keys) else None


def _sort_values(keys: list[Hashable]) -> Sequence[Hashable]:
    """Numbers ascending when every value is a number; otherwise the order they were first seen."""
    numbers = _numbers(keys)
    return keys if numbers is None else numbers


class DistinctBuckets:
    """One bucket per distinct value seen; the key is the value."""

    kind = "distinct"
    limit = DISTINCT_LIMIT

    def key(self, value: object) -> object:
        return value

    def keys(self, values: list) -> list:
        return values

    def finish(self, keys: Iterable[Hashable]) -> tuple[list[Bucket], dict[Hashable, int]]:
        ordered = _sort_values(list(keys))
        return [Bucket(value_label(k), value=k) for k in ordered], {k: i for i, k in enumerate(ordered)}


#: What a cross is made of: any bucketing but another cross.
ComponentBucketing = RangeBuckets | MemberBuckets | DistinctBuckets


class CrossBuckets:
    """The product of the components' buckets; the key is the tuple of the components' keys."""

    kind = "cross"

    def __init__(self, components: Sequence[ComponentBucketing]) -> None:
        self.components = tuple(components)

    def key(self, values: Sequence[object]) -> tuple | None:
        keys = []
        for component, value in zip(self.components, values, strict=True):
            k = component.key(value)
            if k is None:
                return None
            keys.append(k)
        return tuple(keys)

    def keys(self, values: list) -> list:
        """Tuples of the components' keys; a tuple holding None (a part outside its buckets) is ignored."""
        if not values:
            return []
        columns = [component.keys(list(column)) for component, column in
                   zip(self.components, zip(*values, strict=True), strict=True)]
        return list(zip(*columns, strict=True)) if columns else []


Bucketing = ComponentBucketing | CrossBuckets


def bucketing_for(value_type: ValueType, value_range: tuple[float, float] | None,
                  every: float | None) -> ComponentBucketing:
    """The bucketing of a (non-cross) cover item."""
    if value_type.kind == "enum":
        return MemberBuckets(value_type.members)
    if value_type.kind == "bool":
        return MemberBuckets((False, True))
    if value_type.numeric and value_range is not None:
        return RangeBuckets(value_type.kind, value_range[0], value_range[1], every)
    return DistinctBuckets()
