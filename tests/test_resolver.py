"""The resolver on real files: names, types, SI values, instances, keeps, modifiers and errors."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import textwrap
from pathlib import Path

import pytest
from cli_support import example_library_env

from coverage_engine.errors import (
    ArgumentError,
    NameLookupError,
    OscError,
    OscTypeError,
    ParameterFileError,
    UnsupportedFeatureError,
)
from coverage_engine.files.loader import load_scenario_file
from coverage_engine.resolve import model
from coverage_engine.resolve.model import Const, EnumValue


def load(tmp_path: Path, text: str, overrides=None, name: str = "s.osc") -> model.ScenarioFile:
    path = tmp_path / name
    path.write_text("import osc.helpers\n" + textwrap.dedent(text), encoding="utf-8")
    return load_scenario_file(path, overrides)


def actions(behavior: model.Behavior) -> list[model.ActionCall]:
    """All action calls below ``behavior`` in order."""
    if isinstance(behavior, model.ActionCall):
        return [behavior]
    if isinstance(behavior, model.Composite):
        return [a for child in behavior.children for a in actions(child)]
    if isinstance(behavior, model.Modified):
        return actions(behavior.child)
    return []


def logged(scenario: model.Scenario) -> list[object]:
    """The constant messages of the scenario's log actions."""
    result = []
    for call in actions(scenario.body):
        expr = dict(call.arguments)["msg"]
        assert isinstance(expr, Const), expr
        result.append(expr.value)
    return result


def test_physical_values_are_si_and_arithmetic_promotes(tmp_path):
    sf = load(tmp_path, """
        global d: length = 3.2cm
        global t: time = 2.0s + 500ms
        global f: float = 2 * 1.25
        scenario sc:
            do serial:
                log(d)
                log(t)
                log(f)
                log(-(1 + 2))
                log(2 + 3 * 4)
        """)
    values = logged(sf.scenarios[0])
    assert values[0] == pytest.approx(0.032)
    assert values[1:] == [2.5, 2.5, -3, 14]


def test_struct_defaults_keeps_and_inheritance(tmp_path):
    sf = load(tmp_path, """
        struct base_struct:
            x: string = "base_x"
            y: string = "base_y"
        struct test_struct inherits base_struct:
            z: string = "value_z"
        scenario test:
            foo: test_struct with:
                keep(it.x == "override_x")
            do serial:
                log(foo)
                log(foo.z)
        """)
    assert logged(sf.scenarios[0]) == [{"x": "override_x", "y": "base_y", "z": "value_z"}, "value_z"]


def test_enum_values_number_on_from_the_last_explicit_one(tmp_path):
    sf = load(tmp_path, """
        enum e: [a = 4, b, c = 10]
        scenario sc:
            do serial:
                log(e!b)
                log(e!c)
        """)
    assert logged(sf.scenarios[0]) == [EnumValue("b", 5), EnumValue("c", 10)]
    assert repr(EnumValue("b", 5)) == "('b', 5)"


def test_variables_and_wait_conditions_stay_symbolic(tmp_path):
    sf = load(tmp_path, """
        actor robot:
            var count: int = 42
        scenario sc:
            r: robot
            do serial:
                increment(r.count)
                wait r.count == 43
        """)
    scenario = sf.scenarios[0]
    assert [v.key for v in scenario.variables] == ["r.count"]
    body = scenario.body
    assert isinstance(body.children[0], model.ActionCall)
    target = dict(body.children[0].arguments)["target_variable"]
    assert isinstance(target, model.VariableRef) and target.variable.key == "r.count"
    assert isinstance(body.children[1], model.WaitCondition)


def test_modifiers_nest_first_written_outermost(tmp_path):
    sf = load(tmp_path, """
        scenario sc:
            timeout(2s)
            do serial:
                log("x") with:
                    inverter()
                    retry(3)
        """)
    body = sf.scenarios[0].body
    assert isinstance(body, model.Modified) and body.modifier == "timeout"
    assert dict(body.arguments) == {"duration": 2.0}
    outer = body.child.children[0]
    assert outer.modifier == "inverter"
    assert outer.child.modifier == "retry" and dict(outer.child.arguments) == {"count": 3}


def test_keep_sets_an_action_argument(tmp_path):
    sf = load(tmp_path, """
        scenario sc:
            do log() with:
                keep(it.msg == "from keep")
        """)
    assert logged(sf.scenarios[0]) == ["from keep"]


@pytest.mark.parametrize(("body", "error", "column"), [
    ("log(unknown_name)", NameLookupError, 13),
    ("log(msg: 'a', msg: 'b')", ArgumentError, 23),
    ("log('a', foo: 'b')", ArgumentError, 18),
    ("wait elapsed(3)", OscTypeError, 22),
    ("no_such_action()", NameLookupError, 9),
    ("log(1s + 1)", OscTypeError, 13),
    ("log('x') with:\n                    no_such_modifier()", NameLookupError, 13),
])
def test_errors_carry_positions(tmp_path, body, error, column):
    with pytest.raises(error) as info:
        load(tmp_path, f"""
        scenario sc:
            do serial:
                {body}
        """)
    exc = info.value
    assert exc.location is not None and exc.location.file.endswith("s.osc")
    assert exc.location.column == column
    assert exc.source_line is not None and "^" in exc.render()


def test_unknown_type_is_an_error_at_the_type(tmp_path):
    with pytest.raises(NameLookupError, match="unknown type 'unknownType'") as info:
        load(tmp_path, """
        scenario test:
            p: unknownType
            do log("x")
        """)
    assert info.value.location.line == 4


def test_keep_in_is_left_to_the_variation_tool(tmp_path):
    with pytest.raises(UnsupportedFeatureError, match="scenario_variation"):
        load(tmp_path, """
        scenario sc:
            do log() with:
                keep(it.msg in ["a", "b"])
        """)


def test_overrides_convert_to_declared_types(tmp_path):
    text = """
        struct pair:
            a: string = "a"
            b: float = 1.0
        enum colour: [red, green]
        scenario test:
            l: length = 1.0m
            f: float = 1.0
            t: string = "x"
            p: pair
            c: colour = colour!red
            n: list of pair
            do log("x")
        """
    sf = load(tmp_path, text, {"test": {"l": 3, "f": 42, "t": 4.5, "p": {"b": 2}, "c": "green",
                                        "n": [{"a": "q"}]}})
    values = sf.scenarios[0].parameter_values()
    assert values == {"l": 3.0, "f": 42.0, "t": "4.5", "p": {"a": "a", "b": 2.0}, "c": EnumValue("green", 1),
                      "n": [{"a": "q", "b": 1.0}]}
    assert isinstance(values["f"], float)


@pytest.mark.parametrize("overrides", [
    {"nope": {}},
    {"test": {"missing": 1}},
    {"test": {"p": {"zz": 1}}},
    {"test": {"v": 1}},
    {"test": {"derived": "x"}},
    {"test": {"f": "text"}},
])
def test_bad_overrides_are_rejected(tmp_path, overrides):
    text = """
        struct pair:
            a: string = "a"
        scenario test:
            f: float = 1.0
            p: pair
            derived: float = f
            var v: int = 0
            do log("x")
        """
    with pytest.raises(ParameterFileError):
        load(tmp_path, text, overrides)


def test_relative_import_and_unknown_library(tmp_path):
    (tmp_path / "lib.osc").write_text("struct shared:\n    v: int = 5\n", encoding="utf-8")
    sf = load(tmp_path, """
        import "lib.osc"
        scenario sc:
            sh: shared
            do log(sh.v)
        """)
    assert logged(sf.scenarios[0]) == [5]
    with pytest.raises(OscError, match="osc.nope"):
        load(tmp_path, "import osc.nope\nscenario sc:\n    do log('x')\n", name="t.osc")


EXAMPLES = sorted(p for p in (Path(__file__).resolve().parent.parent / "examples").rglob("*.osc")
                  if "build" not in p.parts)
@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_every_example_parses_and_resolves(path, tmp_path):
    """Concrete examples resolve as they are; abstract ones (``keep(… in […])``) through their variants."""
    from coverage_engine.parse.parser import parse_file

    unit = parse_file(path)
    if "import osc.mujoco_drop\n" in unit.text and importlib.util.find_spec("mujoco_drop") is None:
        pytest.fail("the library of examples/mujoco is not installed: pip install -e examples/mujoco (.ci/run does)")
    if "in [" in unit.text and "keep(" in unit.text:
        with pytest.raises(UnsupportedFeatureError, match="scenario_variation"):
            load_scenario_file(path)
        # a continuous range ([1mps..12mps]) is drawn by a sampler; listed values make the full product
        strategy = ["--strategy", "lhs", "--samples", "4", "--seed", "1"] if ".." in unit.text else []
        done = subprocess.run(["scenario_variation", str(path), "-o", str(tmp_path / "out"), *strategy,
                               "--store", f"sqlite:///{tmp_path / 'store.db'}"], capture_output=True, text=True)
        assert done.returncode == 0, done.stdout + done.stderr
        variants = sorted((tmp_path / "out").glob("*.sce"))
        assert len(variants) > 1 and all(load_scenario_file(v).scenarios for v in variants)
        return
    declares_scenario = any(getattr(d, "kind", None) == "scenario" for d in unit.declarations)
    if "import osc.example\n" in unit.text:  # the library of examples/example_library, found by entry point
        env = dict(os.environ, **example_library_env(tmp_path / "site"))
        done = subprocess.run(["scenario_execution", "-n", str(path)], capture_output=True, text=True, env=env)
        assert done.returncode == 0, done.stdout + done.stderr
    elif declares_scenario:
        assert load_scenario_file(path).scenarios


def test_keep_it_equals_sets_a_scenario_parameter(tmp_path):
    sf = load(tmp_path, """
        scenario sc:
            speed: float = 1.0 with:
                keep(it == 2.5)
            do log(speed)
        """)
    assert logged(sf.scenarios[0]) == [2.5]
    assert sf.scenarios[0].parameter_values() == {"speed": 2.5}


def test_sce_parameters_apply_under_command_line_overrides():
    from coverage_engine.files.loader import merge_overrides

    recorded = {"test": {"speed": 3.5, "name": "a"}, "other": {"x": 1}}
    assert merge_overrides(recorded, {"test": {"name": "b"}}) == {
        "test": {"speed": 3.5, "name": "b"}, "other": {"x": 1}}
    assert recorded["test"]["name"] == "a"


def test_parsing_and_resolving_never_import_the_runtime(project_root):
    import subprocess
    import sys

    code = ("import sys\n"
            "from coverage_engine.files.loader import load_scenario_file\n"
            "load_scenario_file(sys.argv[1])\n"
            "heavy = [m for m in ('py_trees', 'rich', 'sqlalchemy', 'executor') if m in sys.modules]\n"
            "assert not heavy, heavy\n")
    done = subprocess.run([sys.executable, "-c", code, str(project_root / "examples/hello_world/hello_world.osc")],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_keep_on_a_variable_sets_its_initial_value(tmp_path):
    sf = load(tmp_path, """
        struct counter:
            var v: int = 2
        scenario sc:
            c: counter with:
                keep(it.v == 9)
            do log(c.v)
        """)
    (variable,) = sf.scenarios[0].variables
    assert variable.key == "c.v" and variable.initial == Const(9)


def test_uint_rejects_negative_values(tmp_path):
    with pytest.raises(OscTypeError, match="negative"):
        load(tmp_path, """
        global b: uint = -1
        scenario sc:
            do log(b)
        """)


@pytest.mark.parametrize(("text", "message", "line"), [
    ("scenario a:\n    do log('x')\n    do log('y')\n", "already has a 'do' body", 4),
    ("struct s:\n    a: s\nscenario sc:\n    p: s\n    do log('x')\n", "contains itself", 3),
    ("scenario sc:\n    do serial:\n        repeat(-3)\n        log('x')\n", "repeat", 4),
    ("scenario sc:\n    do serial:\n        timeout(0s)\n        log('x')\n", "positive time", 4),
    ("scenario sc:\n    do wait elapsed(-1s)\n", "non-negative", 3),
    ("scenario sc:\n    x: int = " + "+".join(["1"] * 5000) + "\n    do log(x)\n", "nested too deeply", 1),
])
def test_meaningless_input_is_a_located_error(tmp_path, text, message, line):
    with pytest.raises(OscError, match=message) as info:
        load(tmp_path, text)
    assert info.value.location.line == line


def test_constructor_argument_errors_point_at_the_argument(tmp_path):
    with pytest.raises(OscTypeError, match="expected length, got time") as info:
        load(tmp_path, """
        import osc.standard
        scenario sc:
            p: position_3d = position_3d(x: 1s)
            do log(p)
        """)
    assert info.value.location.file.endswith("s.osc")
    assert (info.value.location.line, info.value.location.column) == (5, 34)


def test_contradicting_keeps_are_an_error_and_default_keeps_yield(tmp_path):
    with pytest.raises(OscError, match="contradicting constraints on 'p.a': 5 and 4") as info:
        load(tmp_path, """
        struct p:
            a: int = 1
            keep(it.a == 5)
        scenario sc:
            q: p with:
                keep(it.a == 4)
            do log(q.a)
        """)
    assert info.value.location.line == 8
    sf = load(tmp_path, """
        struct p:
            a: int = 1
            keep(default it.a == 5)
        scenario sc:
            q: p with:
                keep(it.a == 4)
            r: p
            do log(q.a)
        """)
    assert sf.scenarios[0].parameter_values() == {"q": {"a": 4}, "r": {"a": 5}}
