"""The syntax builder reads a rule's parts by name (issue 34 item 6): tokens by terminal, built values by
class, optional parts present or absent, and each part-record keeps the span its parent's location needs."""

from __future__ import annotations

import pytest

from coverage_engine.parse import syntax as s
from coverage_engine.parse.lexer import Token
from coverage_engine.parse.parser import parse_text
from coverage_engine.parse.parts import built, maybe_node, maybe_token, node, nodes, token, tokens


def _token(kind: str, value: str, at: int) -> Token:
    return Token(kind, value, at, 1, at + 1, 1, at + 1 + len(value), at + len(value))


def test_a_part_is_found_by_its_terminal_or_its_class_wherever_optional_parts_put_it():
    name = s.QualifiedName(("a",), None)  # type: ignore[arg-type]
    children = [_token("MINUS", "-", 0), _token("NAME", "x", 1), name, _token("NAME", "y", 3)]
    assert token(children, "INT", "NAME").value == "x"
    assert [t.value for t in tokens(children, "NAME")] == ["x", "y"]
    assert maybe_token(children, "HEX") is None
    assert node(children, s.QualifiedName) is name and nodes(children, s.QualifiedName) == (name,)
    assert maybe_node(children, s.TypeRef) is None
    assert built(children) == (name,)


def test_a_part_the_rule_must_have_is_a_loud_builder_bug_when_missing():
    with pytest.raises(LookupError, match="no STRING token"):
        token([_token("NAME", "x", 0)], "STRING")
    with pytest.raises(LookupError, match="no TypeRef"):
        node([], s.TypeRef)


def test_optional_parts_present_and_absent_build_the_same_nodes_and_spans():
    text = ("scenario top:\n"
            "    speed: float = 1.0 with:\n"
            "        keep(it > 0.5)\n"
            "    var n: int\n"
            "    def f(a: int, b: float = 2.0) -> float is external m.f(1)\n"
            "    event e(x: int)\n"
            "    do serial(duration: 3s):\n"
            "        log('a') with:\n"
            "            until elapsed(1s)\n"
            "        emit e(x: 1)\n"
            "        wait elapsed(1s)\n")
    (top,) = parse_text(text, "t.osc").declarations
    speed, n, f, e, do = top.members
    assert (speed.names, speed.default.value, len(speed.with_members)) == (("speed",), 1.0, 1)
    assert (speed.location.line, speed.location.end_line, speed.location.end_column) == (2, 3, 23)
    assert (n.names, n.default) == (("n",), None)
    assert [p.name for p in f.parameters] == ["a", "b"] and f.parameters[1].default.value == 2.0
    assert f.parameters[1].location.end_column == 33 and f.return_type.name.parts == ("float",)
    assert f.external.parts == ("m", "f") and [a.value.value for a in f.external_arguments] == [1]
    assert [p.name for p in e.parameters] == ["x"]
    serial = do.behavior
    assert [a.name for a in serial.arguments] == ["duration"]
    log, emit, wait = serial.members
    assert len(log.with_members) == 1 and (log.location.end_line, log.location.end_column) == (9, 30)
    assert [a.name for a in emit.arguments] == ["x"] and isinstance(wait, s.Wait)
