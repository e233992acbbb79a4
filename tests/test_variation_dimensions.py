"""The dimension finder and the text template, on parsed source."""

from __future__ import annotations

import pytest

from coverage_engine.parse.parser import parse_text
from coverage_engine.variation.dimensions import find_dimensions, one_line
from coverage_engine.variation.template import TextTemplate

TEXT = """import osc.helpers

scenario first:
    do serial:
        greet: log() with:
            keep(it.msg in ["hi", "ho"])
        log() with:
            keep(it.msg in ['x'])
        wait elapsed(1s)

scenario second:
    colour: string
    keep(colour in ['red', 'green', 'blue'])
    do parallel:
        log('a')
        log() with:
            keep(it.msg in [
                'p',   # a comment
                'q'])
        log('c')
"""


@pytest.fixture(scope="module")
def dims():
    return find_dimensions(parse_text(TEXT, "t.osc"), TEXT)


def test_keys_and_order(dims):
    assert [d.key for d in dims] == ["first.greet.msg", "first.log.msg", "second.colour", "second.log[1].msg"]
    assert [len(d.choices) for d in dims] == [2, 1, 3, 2]


def test_values_keep_their_source_text(dims):
    assert [c.text for c in dims[0].choices] == ['"hi"', '"ho"']
    assert [c.stored for c in dims[2].choices] == ["red", "green", "blue"]
    assert dims[3].choices[1].location.line == 19


def test_template_keeps_line_numbers(dims):
    template = TextTemplate.build(TEXT, dims)
    text = template.render([1, 0, 2, 1])
    lines = text.splitlines()
    assert len(lines) == len(TEXT.splitlines())
    assert lines[5].strip() == 'keep(it.msg == "ho")'
    assert lines[12].strip() == "keep(colour == 'blue')"
    assert lines[16].strip() == "keep(it.msg == 'q')"
    assert lines[19].strip() == "log('c')"


def test_one_line():
    assert one_line("pt(x: 1,\n   y: 2)") == "pt(x: 1, y: 2)"
    assert one_line("pt(x: 1, # note\n  y: '#  not a comment')") == "pt(x: 1, y: '#  not a comment')"
    assert one_line("'a  b'") == "'a  b'"
