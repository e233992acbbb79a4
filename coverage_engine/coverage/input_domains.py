"""The buckets of a varied parameter, from what the variation declared (its ``# domain``).

* A **listed** parameter (``keep(lanes in [1, 2, 3])``) has one bucket per declared value, whether a
  run used it or not: a batch of two of six variants leaves the others as holes. Values are listed in
  numeric order when every one is a number (``1.0s 1.5s 2.0s 2.5s``, units allowed), else as
  declared; a value that ran but was not declared (an older generation) is added after them.
* A **drawn** parameter (``keep(speed in [20kph..120kph])`` with a sampler) has equal-width buckets
  spanning the declared range, with round edges in the written unit (``[20 kph..25 kph)``). Their
  width is the ``every`` of a ``cover()`` on the same parameter when it has one in the same unit; else
  it comes from the design's size ``N``: at most ``N / 2`` buckets (a Latin hypercube of ``N`` points
  then puts a point in each, as every bucket holds two of its strata) and at most :data:`MAX_DRAWN_BUCKETS`.
* Without a domain (runs of an ``.osc`` with parameter documents, results of an older release) the
  buckets are the values that ran, numbers in numeric order.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Hashable, Iterable, Sequence
from dataclasses import replace
from importlib import resources

from coverage_engine.coverage.buckets import Bucket, DistinctBuckets, format_number, value_label
from coverage_engine.domains import InputDomain, numeric_value, unit_of

#: Most buckets a drawn range is split into.
MAX_DRAWN_BUCKETS = 20

#: A parameter without a domain and with more numeric values than this is grouped into range buckets.
INPUT_VALUES_LIMIT = 50

#: Bucket widths are one of these times a power of ten.
_NICE_STEPS = (1.0, 2.0, 2.5, 5.0, 10.0)


def nice_width(span: float, most: int) -> float:
    """The smallest round width (1, 2, 2.5 or 5 times a power of ten) that splits ``span`` into at most
    ``most`` buckets."""
    if not span > 0 or not math.isfinite(span) or most < 1:
        return 1.0
    raw = span / most
    if raw < 1e-300:                   # a span too small to split: one bucket
        return span
    power = 10.0 ** math.floor(math.log10(raw))
    for step in _NICE_STEPS:
        width = step * power
        if width >= raw * (1 - 1e-9):
            return width
    return 10 * power


def drawn_bucket_count(domain: InputDomain) -> int:
    """How many buckets a drawn range aims at, from its design's size."""
    samples = domain.samples or domain.count or 2 * MAX_DRAWN_BUCKETS
    return max(1, min(MAX_DRAWN_BUCKETS, samples // 2))


def _spaced(value: float, unit: str) -> str:
    text = format_number(round(value, 10))
    return f"{text} {unit}" if unit else text


class RangeAxis:
    """Round-width buckets over a declared range ``[low..high]``: inner edges are multiples of the width,
    the first and last buckets end at the range's own ends (``[20 kph..25 kph)``, never ``[0 kph..25 kph)``
    for a range from 20); a value's bucket is found by arithmetic."""

    def __init__(self, low: float, high: float, width: float, unit: str) -> None:
        self.low, self.high, self.width, self.unit = low, high, width, unit
        self.start = math.floor(low / width + 1e-9) * width if width > 0 else low
        self.count = max(1, math.ceil((high - self.start) / width - 1e-9)) if high > low and width > 0 else 1

    def index(self, value: float) -> int | None:
        slack = 1e-9 * max(self.width, abs(self.high), abs(self.low), 1e-300)
        if not self.low - slack <= value <= self.high + slack:
            return None
        if self.count == 1:
            return 0
        return min(self.count - 1, max(0, int((value - self.start) // self.width)))

    def buckets(self) -> list[Bucket]:
        if self.count == 1 and self.low == self.high:
            return [Bucket(_spaced(self.low, self.unit), low=self.low, high=self.high)]
        out = []
        for i in range(self.count):
            low = self.low if i == 0 else self.start + i * self.width
            high = self.high if i == self.count - 1 else self.start + (i + 1) * self.width
            closing = "]" if i == self.count - 1 else ")"
            out.append(Bucket(f"[{_spaced(low, self.unit)}..{_spaced(high, self.unit)}{closing}", low=low, high=high))
        return out


def range_axis(domain: InputDomain, every: float | None = None) -> RangeAxis:
    """The buckets of a drawn (or long numeric) parameter; ``every`` from a ``cover()`` in its unit."""
    assert domain.low is not None and domain.high is not None
    span = domain.high - domain.low
    width = every if every and every > 0 and span / every <= 10_000 else nice_width(span, drawn_bucket_count(domain))
    return RangeAxis(domain.low, domain.high, width, domain.unit)


_UNIT_LINE = re.compile(r"^unit\s+(\w+)\s+of\s+\w+\s+is\s+SI\(([^)]*)\)", re.MULTILINE)
_FACTOR = re.compile(r"\bfactor:\s*([-+0-9.eE]+)")
_OFFSET = re.compile(r"\boffset:\s*([-+0-9.eE]+)")


@functools.cache
def unit_scales() -> dict[str, tuple[float, float]]:
    """``unit -> (factor, offset)`` of the standard library's units (``types.osc``): a value in SI is
    ``number * factor + offset``. Read from the library's text, so the two never disagree."""
    text = resources.files("coverage_engine.osc").joinpath("types.osc").read_text(encoding="utf-8")
    scales = {}
    for name, body in _UNIT_LINE.findall(text):
        factor, offset = _FACTOR.search(body), _OFFSET.search(body)
        scales[name] = (float(factor.group(1)) if factor else 1.0, float(offset.group(1)) if offset else 0.0)
    return scales


def _si(value: Hashable) -> float | None:
    number = numeric_value(value)
    if number is None:
        return None
    factor, offset = unit_scales().get(unit_of(value), (1.0, 0.0))
    return number * factor + offset


def numeric_order(values: Sequence[Hashable]) -> list[Hashable] | None:
    """``values`` in numeric order when every one is a number, with or without a unit (``500ms`` before
    ``1s``: units of the standard library compare in SI); else None."""
    numbers = [_si(v) for v in values]
    if not values or any(n is None for n in numbers):
        return None
    order = sorted(range(len(values)), key=lambda i: numbers[i])   # type: ignore[arg-type, return-value]
    return [values[i] for i in order]


def _listed_buckets(domain: InputDomain, seen: list[Hashable]) -> tuple[list[Bucket], dict[Hashable, int]]:
    assert domain.values is not None
    declared = list(dict.fromkeys(v for v in domain.values if isinstance(v, Hashable)))
    known = set(declared)
    extra = [k for k in seen if k not in known]
    ordered = numeric_order(declared) or declared
    ordered += numeric_order(extra) or extra
    return [Bucket(value_label(v), value=v) for v in ordered], {v: i for i, v in enumerate(ordered)}


def _range_buckets(domain: InputDomain, seen: list[Hashable], every: float | None) \
        -> tuple[list[Bucket], dict[Hashable, int]] | None:
    numbers = [numeric_value(key) for key in seen]
    if any(n is None for n in numbers):
        return None            # a value that is no number: bucket the values that ran
    present = [n for n in numbers if n is not None]
    assert domain.low is not None and domain.high is not None
    if present and (min(present) < domain.low or max(present) > domain.high):
        # Runs of another generation drew outside this declaration: the axis spans both.
        domain = replace(domain, low=min(domain.low, *present), high=max(domain.high, *present))
    axis = range_axis(domain, every)
    index: dict[Hashable, int] = {}
    for key, number in zip(seen, present, strict=True):
        index[key] = axis.index(number) or 0
    return axis.buckets(), index


def domain_buckets(domain: InputDomain, seen: list[Hashable], every: float | None = None) \
        -> tuple[list[Bucket], dict[Hashable, int]] | None:
    """The buckets of a parameter declared as ``domain`` and the bucket of each value ``seen`` (None when
    the values that ran do not fit the declaration: the caller buckets what ran)."""
    if domain.values is not None:
        return _listed_buckets(domain, seen)
    if domain.is_range:
        return _range_buckets(domain, seen, every)
    return None


class InputValueBuckets(DistinctBuckets):
    """The values of a varied parameter (the keys the merge counts under); :meth:`finish` buckets them by
    ``domain``, what the variation declared, when it is known, else by what ran."""

    kind = "input"
    limit = 100_000

    def finish(self, keys: Iterable[Hashable], domain: InputDomain | None = None,
               every: float | None = None) -> tuple[list[Bucket], dict[Hashable, int]]:
        seen = list(keys)
        if domain is not None:
            found = domain_buckets(domain, seen, every)
            if found is not None:
                return found
        ordered = numeric_order(seen)
        if ordered is None or len(ordered) <= INPUT_VALUES_LIMIT:
            ordered = ordered or seen
            return [Bucket(value_label(k), value=k) for k in ordered], {k: i for i, k in enumerate(ordered)}
        numbers = [n for n in map(numeric_value, ordered) if n is not None]   # all numbers: see numeric_order
        units = {unit_of(k) for k in ordered}
        ran = InputDomain("", low=min(numbers), high=max(numbers), unit=units.pop() if len(units) == 1 else "",
                          count=len(ordered))
        axis = range_axis(ran)
        return axis.buckets(), {k: (axis.index(n) or 0) if n is not None else 0
                               for k, n in zip(ordered, numbers, strict=True)}
