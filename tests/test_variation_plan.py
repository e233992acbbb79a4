"""The variation plan: dimensions, order of the product, and per-value checking with a scripted resolver.

The resolver is replaced by a function that fails for chosen values, so these tests pin the checking
logic (which values are tried, what is skipped) without depending on the real resolver.
"""

from __future__ import annotations

import pytest

from coverage_engine.errors import OscError
from coverage_engine.location import Location
from coverage_engine.variation.choice import plan_variation

TWO_KEEPS = """import osc.helpers

scenario test:
    do serial:
        log() with:
            keep(it.msg in ['A1', 'A2'])
        log() with:
            keep(it.msg in ['B1', 'B2', 'B3'])
"""


class Scripted:
    """Fails when the text contains one of ``bad`` (error at that line); counts calls."""

    def __init__(self, *bad: str, file: str = "") -> None:
        self.bad, self.file, self.calls = bad, file, []

    def __call__(self, text: str, overrides):
        self.calls.append((text, overrides))
        for needle in self.bad:
            if needle in text:
                line = text[:text.index(needle)].count("\n") + 1
                raise OscError(f"cannot use {needle}", Location(self.file, line, 1))
        return object()


def _plan(tmp_path, text, *bad, documents=None):
    path = tmp_path / "main.osc"
    path.write_text(text)
    resolver = Scripted(*bad, file=str(path))
    return plan_variation(path, documents, resolver=resolver), resolver


def test_product_order_first_keep_slowest(tmp_path):
    plan, resolver = _plan(tmp_path, TWO_KEEPS)
    combos = [plan.shown_assignment(c) for _, c, _ in plan.combinations()]
    assert [(a["test.log[0].msg"], a["test.log[1].msg"]) for a in combos] == [
        ("'A1'", "'B1'"), ("'A1'", "'B2'"), ("'A1'", "'B3'"), ("'A2'", "'B1'"), ("'A2'", "'B2'"), ("'A2'", "'B3'")]
    assert plan.total == plan.valid_count() == 6
    assert len(resolver.calls) == 1 + 1 + 2  # baseline, then each other value once


def test_concrete_text_replaces_the_list(tmp_path):
    plan, _ = _plan(tmp_path, TWO_KEEPS)
    text = plan.concrete_text((1, 2))
    assert "keep(it.msg == 'A2')" in text and "keep(it.msg == 'B3')" in text and " in [" not in text
    assert text.count("\n") == TWO_KEEPS.count("\n")


def test_bad_value_skips_its_combinations(tmp_path):
    plan, _ = _plan(tmp_path, TWO_KEEPS, "== 'B2'")
    assert plan.valid_count() == 4
    skipped = [i for i, _, r in plan.combinations() if r is not None]
    assert skipped == [1, 4]
    (rejection,) = plan.rejections
    assert rejection.shown == {"test.log[1].msg": "'B2'"}
    assert rejection.location.line == 8 and rejection.skipped == 2


def test_bad_first_value_is_found_from_the_baseline(tmp_path):
    plan, _ = _plan(tmp_path, TWO_KEEPS, "== 'A1'")
    assert plan.valid_count() == 3
    assert [i for i, _, r in plan.combinations() if r is None] == [3, 4, 5]


def test_unattributable_baseline_error_is_searched(tmp_path):
    plan, resolver = _plan(tmp_path, TWO_KEEPS, "== 'B1'")
    resolver_bad_line = Scripted("== 'B1'", file="elsewhere.osc")  # error outside the file: no line to go by
    plan = plan_variation(tmp_path / "main.osc", resolver=resolver_bad_line)
    assert plan.valid_count() == 4
    assert plan.rejections[0].shown == {"test.log[1].msg": "'B1'"}


def test_file_error_is_raised(tmp_path):
    with pytest.raises(OscError, match="cannot use scenario"):
        _plan(tmp_path, TWO_KEEPS, "scenario")


def test_multiline_list_keeps_line_numbers(tmp_path):
    text = ("import osc.helpers\n\nscenario test:\n    do serial:\n        log() with:\n"
            "            keep(it.msg in ['a',  # first\n                            'b'])\n"
            "        log('after')\n")
    plan, _ = _plan(tmp_path, text)
    concrete = plan.concrete_text((1,))
    assert concrete.splitlines()[7] == "        log('after')"
    assert "keep(it.msg == 'b')" in concrete


def test_no_keep_gives_one_model(tmp_path):
    plan, resolver = _plan(tmp_path, "import osc.helpers\nscenario quick:\n    do log('x')\n")
    assert plan.dimensions == () and plan.total == 1
    assert list(plan.combinations()) == [(0, (), None)]
    assert plan.scenario == "quick" and len(resolver.calls) == 1


def test_documents_are_the_last_dimension(tmp_path):
    plan, resolver = _plan(tmp_path, TWO_KEEPS, documents=[{}, {"test": {}}])
    assert plan.total == 12
    assert [c for _, c, _ in plan.combinations()][:3] == [(0, 0, 0), (0, 0, 1), (0, 1, 0)]
    assert plan.keys[-1] == "parameter_document"
    assert plan.overrides((0, 0, 1)) == {"test": {}}


def test_same_parameter_keeps_share_a_slot(tmp_path):
    text = ("scenario s:\n    x: int with:\n        keep(it in [1, 2])\n    keep(x in [2, 3])\n"
            "    do serial:\n        wait elapsed(1s)\n")
    plan, resolver = _plan(tmp_path, text)
    assert len(plan.slots) == 1 and plan.slots[0].count == 4
    assert len(resolver.calls) == 4


def test_scenario_parameter_and_struct_values(tmp_path):
    text = """struct base_struct:
    base1: string

scenario test:
    param1: base_struct with:
        keep(it.base1 in ['foo1', 'foo2'])
    speed: float
    keep(speed in [1.5, -2.0])
    do serial:
        foo() with:
            keep(it.p in [base_struct(base1: 'x'), base_struct(base1: 'y')])
"""
    plan, _ = _plan(tmp_path, text)
    assert plan.keys == ["test.param1.base1", "test.speed", "test.foo.p"]
    assert plan.stored() == [["foo1", "foo2"], [1.5, -2.0], ["base_struct(base1: 'x')", "base_struct(base1: 'y')"]]


RANGE_AND_LIST = """import osc.helpers

scenario test:
    speed: speed with:
        keep(it in [10kph..50kph])
    lanes: int with:
        keep(it in [1, 2, 3])
    do log('x')
"""


def test_design_points_map_unit_coordinates_onto_each_axis(tmp_path):
    from coverage_engine.proposals import Proposal, header_proposal
    from coverage_engine.variation.checking import check_values
    from coverage_engine.variation.choice import choose_all
    from coverage_engine.variation.design import design_points
    from coverage_engine.variation.output import generate
    from coverage_engine.variation.plan import parse_variation

    path = tmp_path / "main.osc"
    path.write_text(RANGE_AND_LIST)
    parsed = parse_variation(path)
    assert parsed.keys == ["test.speed", "test.lanes"]
    planned = design_points(parsed, [[0.0, 0.25, 1.0], [0.0, 0.5, 1.0]], note="strategy boundary, round 2",
                            samples=3, proposal=Proposal(2, "boundary", ("r1",)))
    assert [planned.assignment(row) for row in planned.rows] == [
        {"test.speed": 10.0, "test.lanes": 1}, {"test.speed": 20.0, "test.lanes": 2},
        {"test.speed": 50.0, "test.lanes": 3}]
    assert parsed.dimensions[0].choices == ()          # the parsed stage is untouched by the design
    checked = check_values(planned, Scripted())
    plan = choose_all(checked)
    assert plan.total == plan.valid_count() == 3 and planned.rows == plan.rows
    result = generate(plan, tmp_path / "out")
    assert result.written == 3
    text = (tmp_path / "out" / "main1.sce").read_text()
    assert header_proposal(text) == Proposal(2, "boundary", ("r1",))
    assert "# strategy boundary, round 2\n" in text
