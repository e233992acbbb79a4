"""Buckets and the plan: which bucket a value falls in, and how a plan file is read."""

from __future__ import annotations

import pytest
import yaml

from coverage_engine.coverage.buckets import MemberBuckets, RangeBuckets
from coverage_engine.coverage.errors import PlanError
from coverage_engine.coverage.input_domains import InputValueBuckets
from coverage_engine.coverage.plan import parse_plan


def labels(bucketing) -> list[str]:
    return [b.label for b in bucketing.finish([])[0]]


def test_float_range_buckets_are_half_open_and_the_last_is_closed():
    speed = RangeBuckets("float", 0, 30, 10)
    assert labels(speed) == ["[0..10)", "[10..20)", "[20..30]"]
    assert speed.keys([0, 9.99, 10, 29.5, 30, -0.1, 30.01]) == [0, 0, 1, 2, 2, None, None]
    assert [speed.key(v) for v in (0, 9.99, 10, 29.5, 30, -0.1, 30.01)] == [0, 0, 1, 2, 2, None, None]


def test_a_range_that_is_not_a_whole_number_of_widths_ends_at_its_high():
    ragged = RangeBuckets("float", 0, 25, 10)
    assert labels(ragged) == ["[0..10)", "[10..20)", "[20..25]"]
    assert ragged.keys([24.9, 25, 25.5, 12]) == [2, 2, None, 1]


def test_int_buckets_hold_every_whole_numbers():
    assert labels(RangeBuckets("int", -2, 2, 1)) == ["-2", "-1", "0", "1", "2"]
    lanes = RangeBuckets("int", 1, 10, 4)
    assert labels(lanes) == ["1..4", "5..8", "9..10"]
    assert lanes.keys([1, 4, 5, 10, 11, 0]) == [0, 0, 1, 2, None, None]


def test_a_range_without_every():
    assert labels(RangeBuckets("int", 1, 5, None)) == ["1", "2", "3", "4", "5"]
    assert len(labels(RangeBuckets("int", 0, 99, None))) == 10
    assert labels(RangeBuckets("float", 0, 1, None))[:2] == ["[0..0.1)", "[0.1..0.2)"]


def test_members_and_many_numeric_inputs():
    assert MemberBuckets(("left", "right")).keys(["right", "up"]) == ["right", None]
    values = list(range(100))
    defs, index = InputValueBuckets().finish(values)
    assert len(defs) == 20 and defs[0].label == "[0..5)" and index[0] == 0 and index[99] == 19
    defs, index = InputValueBuckets().finish([30, 10, 20])
    assert [d.label for d in defs] == ["10", "20", "30"]


def test_a_plan_file():
    plan = parse_plan("at_least: 2\nitems:\n  a.b: {weight: 3}\n  'input:*': {weight: 0, at_least: 1}\n")
    assert plan.for_item("a.b").weight == 3 and plan.for_item("a.b").at_least == 2
    assert plan.for_item("input:x").weight == 0 and plan.for_item("other").at_least == 2
    assert plan.unmatched(["a.b"]) == ["input:*"]


@pytest.mark.parametrize(("text", "message"), [
    ("items:\n  a: {weight: -1}\n", "p.yaml:2:15: error: weight must be a number, 0 or more (got '-1')"),
    ("goal: 90\n", "p.yaml:1:1: error: unknown key 'goal' in the plan (known: at_least, weight, items)"),
    ("items:\n  a: {at_least: 2.5}\n", "p.yaml:2:17: error: at_least must be a whole number of hits, 1 or more "
                                        "(got '2.5')"),
    ("items:\n  a: {}\n  a: {}\n", "p.yaml:3:3: error: 'a' appears twice in 'items'"),
    ("items: [a\n", "p.yaml:2:1: error: not valid YAML: " + (   # libyaml's words where PyYAML uses it
        "did not find expected ',' or ']'" if yaml.__with_libyaml__ else "expected ',' or ']', but got '<stream end>'")),
])
def test_plan_errors_point_at_the_value(text, message):
    with pytest.raises(PlanError) as caught:
        parse_plan(text, "p.yaml")
    assert str(caught.value) == message
