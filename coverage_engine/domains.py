"""What a variation declared for each varied parameter, as the ``# domain`` lines of a ``.sce`` header.

Input coverage must be measured against what the variation *declared* (``keep(lanes in [1, 2, 3])``:
three buckets, even when a batch ran only one variant), not against the values that happened to run.
So every ``.sce`` says, once per varied parameter, in a header comment::

    # domain {"key": "road_test.lanes", "values": [1, 2, 3]}
    # domain {"key": "brake.speed", "range": [20.0, 120.0], "unit": "kph", "samples": 60}

``values`` are the declared values as the assignment stores them (a listed ``30kph`` is the text
``"30kph"``); ``range`` is a continuous range the variation drew from (its unit as written, and
``samples``, the size of the design, from which the report sizes its buckets so that an LHS or Sobol
design can fill them). A list of more than :data:`MAX_LISTED` numbers is written as its range (and
``count``): the report groups it into range buckets anyway. The lines are comments, so readers that
do not know them (YAML, an older release) are not affected; they are JSON, so they read back exactly.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from coverage_engine.limits import read_bounded

#: The prefix of a domain line.
DOMAIN_PREFIX = "# domain "

#: Declared lists longer than this are written as their range when every value is a number.
MAX_LISTED = 200

#: Longest domain line written or read back (a longer declaration is not written: the report then buckets
#: the values that ran; a longer line read is ignored, so a report is never held up by one file).
MAX_DOMAIN_LINE = 64 * 1024

#: How much of the start of a ``.sce`` text holds its header (the value comments and the domain lines):
#: what readers that want only the header read.
HEADER_CHARS = 256 * 1024

#: A number with its unit as the variation stores a listed physical value (``30kph``, ``-2.5m/s``).
_NUMBER_WITH_UNIT = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z_][\w/^]*)?\s*")


@dataclass(frozen=True)
class InputDomain:
    """The declared values of one varied parameter (``values``), or the continuous range it was drawn from."""

    key: str
    values: tuple[object, ...] | None = None
    low: float | None = None
    high: float | None = None
    unit: str = ""
    samples: int | None = None
    count: int | None = None

    @property
    def is_range(self) -> bool:
        return self.values is None and self.low is not None and self.high is not None

    @property
    def drawn(self) -> bool:
        """Whether the variation drew this parameter's values from a continuous range (a sampler)."""
        return self.is_range and self.count is None

    def merged(self, other: InputDomain) -> InputDomain:
        """Both declarations at once (two generations of one source may declare more values, a wider range)."""
        if self.values is not None and other.values is not None:
            extra = tuple(v for v in other.values if v not in self.values)
            return InputDomain(self.key, values=self.values + extra)
        if self.is_range and other.is_range:
            assert self.low is not None and self.high is not None and other.low is not None and other.high is not None
            samples = max(self.samples or 0, other.samples or 0) or None
            return InputDomain(self.key, low=min(self.low, other.low), high=max(self.high, other.high),
                               unit=self.unit or other.unit, samples=samples,
                               count=None if self.count is None or other.count is None else max(self.count, other.count))
        return self


def drawn_units_of(domains: Iterable[InputDomain]) -> dict[str, str]:
    """The unit of each parameter a sampler drew (their values are shown rounded, with the unit)."""
    return {domain.key: domain.unit for domain in domains if domain.drawn}


def drawn_text(value: float, unit: str = "") -> str:
    """A drawn number as headers and testcase names show it: 4 significant digits and its unit
    (``116.2kph``, ``12350ms``); the exact value stays in the assignment and the JUnit properties."""
    if not math.isfinite(value):
        return f"{value}{unit}"
    rounded = float(f"{value:.4g}")
    text = str(int(rounded)) if rounded.is_integer() and abs(rounded) < 1e15 else repr(rounded)
    return f"{text}{unit}"


def numeric_value(value: object) -> float | None:
    """The number in a stored value: ``2.5``, ``"2.5s"``, ``"30kph"``; None for anything else."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, str):
        match = _NUMBER_WITH_UNIT.fullmatch(value)
        if match is not None:
            return float(match.group(1))
    return None


def unit_of(value: object) -> str:
    """The unit written after a stored number (``"30kph"`` → ``kph``), "" when there is none."""
    if isinstance(value, str):
        match = _NUMBER_WITH_UNIT.fullmatch(value)
        if match is not None:
            return match.group(2) or ""
    return ""


def listed_domain(key: str, values: Sequence[object]) -> InputDomain:
    """The domain of a listed dimension; a long list of numbers becomes its range."""
    if len(values) > MAX_LISTED:
        numbers = [numeric_value(v) for v in values]
        if all(n is not None for n in numbers):
            units = {unit_of(v) for v in values}
            present = [n for n in numbers if n is not None]
            return InputDomain(key, low=min(present), high=max(present), unit=units.pop() if len(units) == 1 else "",
                               count=len(values))
    return InputDomain(key, values=tuple(values))


def domain_line(domain: InputDomain) -> str:
    """The header line of ``domain`` (ending in a line break); "" when it would be longer than
    :data:`MAX_DOMAIN_LINE` (thousands of long listed texts: the report buckets what ran instead)."""
    body: dict[str, object] = {"key": domain.key}
    if domain.values is not None:
        body["values"] = list(domain.values)
    else:
        body["range"] = [domain.low, domain.high]
        if domain.unit:
            body["unit"] = domain.unit
        if domain.samples is not None:
            body["samples"] = domain.samples
        if domain.count is not None:
            body["count"] = domain.count
    line = DOMAIN_PREFIX + json.dumps(body, ensure_ascii=True, separators=(", ", ": ")) + "\n"
    return line if len(line) <= MAX_DOMAIN_LINE else ""


def _domain(body: object) -> InputDomain | None:
    if not isinstance(body, dict) or not isinstance(body.get("key"), str):
        return None
    key = body["key"]
    values = body.get("values")
    if isinstance(values, list):
        if not all(isinstance(v, (str, int, bool)) or (isinstance(v, float) and math.isfinite(v)) for v in values):
            return None
        return InputDomain(key, values=tuple(values))
    ends = body.get("range")
    if not (isinstance(ends, list) and len(ends) == 2 and all(numeric_value(e) is not None for e in ends)):
        return None
    low, high = float(ends[0]), float(ends[1])
    if not (low <= high and math.isfinite(high - low)):
        return None
    unit = body.get("unit") if isinstance(body.get("unit"), str) else ""
    samples = body.get("samples")
    count = body.get("count")
    return InputDomain(key, low=low, high=high, unit=str(unit),
                       samples=samples if isinstance(samples, int) and samples > 0 else None,
                       count=count if isinstance(count, int) and count > 0 else None)


def read_domains(lines: Iterable[str]) -> list[InputDomain]:
    """The domains of the ``# domain`` lines among ``lines`` (the head of a ``.sce``); bad lines are skipped."""
    found = []
    for line in lines:
        if not line.startswith(DOMAIN_PREFIX) or len(line) > MAX_DOMAIN_LINE:
            continue
        try:
            body = json.loads(line[len(DOMAIN_PREFIX):])
        except (ValueError, RecursionError):    # RecursionError: brackets nested thousands deep
            continue
        domain = _domain(body)
        if domain is not None:
            found.append(domain)
    return found


#: Largest ``declared.json`` read.
MAX_DECLARED_BYTES = 16 * 1024 * 1024


def declared_text(domains: Iterable[InputDomain]) -> str:
    """The text of a ``declared.json``: one domain line's JSON per parameter, in a list."""
    lines = [line[len(DOMAIN_PREFIX):].rstrip("\n") for line in map(domain_line, domains) if line]
    return '{"format": "scenario-coverage/declared", "domains": [\n ' + ",\n ".join(lines) + "\n]}\n"


def read_declared(path: str) -> list[InputDomain]:
    """The domains of a ``declared.json`` ([] when it is missing, too big or not one); never follows a link."""
    data = read_bounded(path, MAX_DECLARED_BYTES)
    if data is None:
        return []
    try:
        document = json.loads(data.decode("utf-8"))
    except (ValueError, RecursionError):
        return []
    if not isinstance(document, dict) or document.get("format") != "scenario-coverage/declared" \
            or not isinstance(document.get("domains"), list):
        return []
    return [d for d in map(_domain, document["domains"]) if d is not None]


def header_domains(text: str) -> list[InputDomain]:
    """The domains declared in the header of a ``.sce`` text (the comment lines before its first key)."""
    lines = []
    for line in text.split("\n"):
        if not line.startswith("#"):
            break
        lines.append(line)
    return read_domains(lines)
