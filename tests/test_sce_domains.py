"""The ``# domain`` header lines of a ``.sce`` and the buckets of a varied parameter made from them.

Pure functions with exact answers (no files): what a variation declares reads back exactly, hostile or
broken lines are skipped rather than crashing a report, and range buckets have round inner edges, end
at the declared ends and hold every value of the range, the ends included.
"""

from __future__ import annotations

import pytest

from coverage_engine.coverage.input_domains import InputValueBuckets, nice_width, numeric_order, range_axis
from coverage_engine.domains import (
    MAX_DOMAIN_LINE,
    InputDomain,
    domain_line,
    drawn_text,
    header_domains,
    listed_domain,
    read_domains,
)


@pytest.mark.parametrize("domain", [
    InputDomain("s.lanes", values=(1, 2, 3)),
    InputDomain("s.msg", values=("Hello", "a \u001b[2J b", 'quo"te')),
    InputDomain("s.speed", low=20.0, high=120.0, unit="kph", samples=60),
    InputDomain("s.n", low=-5.0, high=-1.0, count=500),
])
def test_a_domain_reads_back_exactly(domain):
    line = domain_line(domain)
    assert line.endswith("\n") and line.isascii() and "\u001b" not in line
    assert read_domains([line.rstrip("\n")]) == [domain]


@pytest.mark.parametrize("line", [
    "# domain " + "[" * 5000 + "]" * 5000,                            # nesting past the recursion limit
    '# domain {"key": "s.x", "range": [-1.7e308, 1.7e308]}',           # a span that is not finite
    '# domain {"key": "s.x", "range": [5, 1]}',                        # ends the wrong way round
    '# domain {"key": "s.x", "values": [[1, 2]]}',                     # a value that is no scalar
    '# domain {"key": 3, "values": [1]}',                              # a key that is no text
    "# domain not json",
    '# domain {"key": "s.x", "values": [1]' + " " * MAX_DOMAIN_LINE + "}",   # too long to read
])
def test_a_broken_or_hostile_line_is_skipped(line):
    assert read_domains([line]) == []


def test_the_header_ends_at_the_first_key_and_a_long_list_becomes_its_range():
    text = domain_line(InputDomain("s.a", values=(1,))) + "format_version: 2\n" + domain_line(
        InputDomain("s.b", values=(2,)))
    assert [d.key for d in header_domains(text)] == ["s.a"]
    long = listed_domain("s.n", [f"{v}m" for v in range(1000)])
    assert long == InputDomain("s.n", low=0.0, high=999.0, unit="m", count=1000) and not long.drawn
    assert domain_line(InputDomain("s.t", values=tuple("x" * 100 for _ in range(1000)))) == ""   # too long


def test_two_generations_merge_their_declarations():
    first, second = InputDomain("k", values=(1, 2)), InputDomain("k", values=(2, 3))
    assert first.merged(second) == InputDomain("k", values=(1, 2, 3))
    wide = InputDomain("k", low=0.0, high=5.0, unit="m", samples=10).merged(InputDomain("k", low=2.0, high=9.0,
                                                                                          unit="m", samples=40))
    assert (wide.low, wide.high, wide.samples) == (0.0, 9.0, 40)


@pytest.mark.parametrize(("value", "text"), [(116.2345, "116.2kph"), (12345.6, "12350kph"), (0.000123456, "0.0001235kph"),
                                             (2.0, "2kph")])
def test_drawn_values_are_shown_with_four_significant_digits(value, text):
    assert drawn_text(value, "kph") == text


def test_round_widths_and_clipped_ends():
    assert [nice_width(100, n) for n in (20, 10, 7, 3)] == [5, 10, 20, 50]
    axis = range_axis(InputDomain("k", low=20.0, high=120.0, unit="kph", samples=60))
    labels = [b.label for b in axis.buckets()]
    assert labels[0] == "[20 kph..25 kph)" and labels[-1] == "[115 kph..120 kph]" and len(labels) == 20
    assert axis.index(20.0) == 0 and axis.index(120.0) == 19 and axis.index(24.999) == 0 and axis.index(25.0) == 1
    assert axis.index(19.0) is None and axis.index(121.0) is None
    negative = range_axis(InputDomain("k", low=-1.0, high=1.0, samples=8))
    assert [b.label for b in negative.buckets()] == ["[-1..-0.5)", "[-0.5..0)", "[0..0.5)", "[0.5..1]"]
    single = range_axis(InputDomain("k", low=5.0, high=5.0, unit="m", samples=10))
    assert [b.label for b in single.buckets()] == ["5 m"] and single.index(5.0) == 0


def test_declared_values_are_buckets_in_numeric_order_with_what_ran_beyond_them():
    defs, index = InputValueBuckets().finish(["2.5s", "7s"], InputDomain("k", values=("2.5s", "1.0s", "500ms")))
    assert [d.label for d in defs] == ["500ms", "1.0s", "2.5s", "7s"] and (index["2.5s"], index["7s"]) == (2, 3)
    defs, index = InputValueBuckets().finish([30.0, 150.0], InputDomain("k", low=20.0, high=120.0, samples=20))
    assert defs[-1].label == "[140..150]" and index[150.0] == len(defs) - 1      # the axis widens to what ran
    assert numeric_order(["b", "a"]) is None
