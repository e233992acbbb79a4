"""Grammar features of the parser: what each construct becomes, and exact source spans."""

from __future__ import annotations

import pytest

from coverage_engine.parse import syntax as s
from coverage_engine.parse.parser import parse_file, parse_text


def decls(text: str):
    return parse_text(text, "t.osc").declarations


def default_of(expr_text: str):
    (decl,) = decls(f"global g: float = {expr_text}\n")
    return decl.default


def test_imports_both_forms():
    unit = parse_text('import osc.helpers\nimport "lib/my file.osc"\n', "t.osc")
    assert [(i.path, i.is_file) for i in unit.imports] == [("osc.helpers", False), ("lib/my file.osc", True)]


def test_types_units_enums():
    t, u, e = decls("type speed is SI(m: 1, s: -1)\nunit kmph of speed is SI(m: 1, s: -1, factor: 0.27, offset: 0)\n"
                    "enum colour: [\n    red,\n    green = 3,\n    blue = 0x10\n]\n")
    assert t.exponents == (("m", 1), ("s", -1))
    assert (u.name, u.physical_type, u.factor, u.offset) == ("kmph", "speed", 0.27, 0.0)
    assert [(m.name, m.value) for m in e.members] == [("red", None), ("green", 3), ("blue", 16)]


def test_declarations_members_and_behaviours():
    text = '''
action robot.move inherits base.act:
    speed, accel: float = 1.0 with:
        keep(it > 0.5)
    items: list of string = []
    var count: int = 0
    event arrived
    def twice(n: int = 2) -> int is external mod.fn()
    keep(default speed == 1.0)
    timeout(60s)
scenario sc:
    do main: serial(duration: 3s):
        lbl: log("x")
        parallel:
            wait elapsed(1s)
            wait @robot.arrived
        emit done(code: 1)
        call lib.factorial(4)
        repeat()
    with:
        inverter()
'''
    action, scenario = decls(text)
    assert action.kind == "action" and action.name.parts == ("robot", "move")
    assert action.parent.parts == ("base", "act")
    param, items, var, event, method, keep, modifier = action.members
    assert param.names == ("speed", "accel") and isinstance(param.with_members[0], s.KeepConstraint)
    assert items.type.is_list and items.default == s.ListExpr((), items.default.location)
    assert isinstance(var, s.VariableDecl) and isinstance(event, s.EventDecl)
    assert method.external.dotted == "mod.fn" and method.parameters[0].default.value == 2
    assert keep.is_default and isinstance(modifier, s.ModifierInvocation)
    (do,) = scenario.members
    comp = do.behavior
    assert (comp.kind, comp.label, comp.arguments[0].name) == ("serial", "main", "duration")
    assert isinstance(comp.with_members[0], s.ModifierInvocation)
    labelled, par, emit, call, repeat = comp.members
    assert labelled.label == "lbl" and labelled.name.parts == ("log",)
    assert isinstance(par.members[1].condition, s.EventRef) and par.members[1].condition.path == ("robot", "arrived")
    assert emit.event == "done" and emit.arguments[0].name == "code"
    assert isinstance(call.call.callee, s.MemberAccess)
    assert isinstance(repeat, s.Invocation)  # the resolver decides it is a modifier


@pytest.mark.parametrize(("text", "shape"), [
    ("1 + 2 * 3", ("+", 1, ("*", 2, 3))),
    ("(1 + 2) * 3", ("*", ("+", 1, 2), 3)),
    ("1 - 2 - 3", ("-", ("-", 1, 2), 3)),
    ("not 5 > 2 and true", ("and", ("not", (">", 5, 2)), True)),
    ("a or b and c", ("or", "a", ("and", "b", "c"))),
    ("-a * b", ("*", ("-", "a"), "b")),
    ("- (1 + 2)", ("-", ("+", 1, 2))),
    ("x in [1, 2]", ("in", "x", [1, 2])),
    ("a ? 1 : 2", ("?", "a", 1, 2)),
    ("-3", -3),
])
def test_expression_precedence(text, shape):
    def show(node):
        if isinstance(node, s.BinaryOp):
            return (node.op, show(node.left), show(node.right))
        if isinstance(node, s.UnaryOp):
            return (node.op, show(node.operand))
        if isinstance(node, s.Ternary):
            return ("?", show(node.condition), show(node.if_true), show(node.if_false))
        if isinstance(node, s.ListExpr):
            return [show(i) for i in node.items]
        if isinstance(node, s.Identifier):
            return node.name
        return node.value
    assert show(default_of(text)) == shape


def test_literals():
    assert default_of("-2.0rad") == s.PhysicalLiteral(-2.0, "rad", default_of("-2.0rad").location)
    assert default_of("1.0e3m").number == 1000.0 and default_of("500ms").unit == "ms"
    assert default_of("0x1F").value == 31 and default_of(".5").value == 0.5
    assert default_of("'a\\tb'").value == "a\tb" and default_of('"é\\u00e9"').value == "éé"
    assert default_of('"""two\nlines"""').value == "two\nlines"
    assert default_of("colour!red") == s.EnumValueRef("colour", "red", default_of("colour!red").location)
    assert isinstance(default_of("[1m..2m]"), s.RangeExpr)
    assert default_of("|odd name|").name == "odd name"
    assert default_of("größe").name == "größe"
    call = default_of("position_3d(x: 1m, y: 2m)")
    assert isinstance(call, s.Call) and [a.name for a in call.arguments] == ["x", "y"]


def test_spans_are_exact():
    text = "scenario a:\n    p: speed = 1mps with:\n        keep(it in [1mps, 2mps])  # c\n    do log()\n"
    (sc,) = decls(text)
    keep = sc.members[0].with_members[0]
    assert text[keep.location.start_pos:keep.location.end_pos] == "keep(it in [1mps, 2mps])"
    binop = keep.expression
    assert text[binop.location.start_pos:binop.location.end_pos] == "it in [1mps, 2mps]"
    lst = binop.right
    assert text[lst.location.start_pos:lst.location.end_pos] == "[1mps, 2mps]"
    assert (keep.location.line, keep.location.column) == (3, 9)


@pytest.mark.parametrize("variant", [
    lambda t: t.replace("\n", "\r\n"),
    lambda t: t.replace("    ", "\t"),
    lambda t: t.rstrip("\n"),
    lambda t: "# leading comment\n\n" + t + "   # trailing comment",
])
def test_layout_variants(variant):
    text = "scenario a:\n    do serial:\n        log('x')\n        wait elapsed(1s)\n"
    (sc,) = decls(variant(text))
    assert len(sc.members[0].behavior.members) == 2


def test_continuation_lines_and_comments_inside_brackets():
    (sc,) = decls("scenario a:\n    do log(\n        # why\n        'x'\n    )\n")
    assert sc.members[0].behavior.arguments[0].value.value == "x"


def test_soft_keywords_are_names_elsewhere():
    (st,) = decls("struct s:\n    unit: string\n    offset: float\n    factor: float\n")
    assert [m.names[0] for m in st.members] == ["unit", "offset", "factor"]


def test_libraries_and_examples_parse(tmp_path):
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    files = sorted((root / "coverage_engine" / "osc").glob("*.osc")) + sorted((root / "examples").rglob("*.osc"))
    assert files
    for f in files:
        parse_file(f)
