"""Property-based round trip of ``.sce`` files: what scenario_variation writes is what the runtime reads.

Every varied value (any Unicode string, float, int, enum member) and every model text must come back
unchanged, character for character, through the real writer (:class:`SceTemplate`) and reader.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

from hypothesis import example, given, settings
from hypothesis import strategies as st

from coverage_engine.files.sce import parse_sce
from coverage_engine.files.sce_writer import SceTemplate, render_sce

BIN = Path(sys.executable).parent

#: Floats including the awkward ones: signed zero, huge, tiny, infinite, not a number.
FLOATS = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                   st.sampled_from([-0.0, 0.0, 1e300, -1e300, 5e-324, 1e-5, 0.1]))
#: Enum members are stored by name.
ENUM_MEMBERS = st.sampled_from(["red", "green", "yellow_blinking"])
VALUES = st.one_of(st.text(), FLOATS, st.integers(), st.integers(min_value=-2**70, max_value=2**70),
                   ENUM_MEMBERS, st.booleans())


def _same(a: object, b: object) -> bool:
    """Equal, with nan equal to nan and the sign of zero compared."""
    if isinstance(a, float) and isinstance(b, float):
        if math.isnan(a):
            return math.isnan(b)
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
    return type(a) is type(b) and a == b


@settings(max_examples=300, deadline=None)
@given(key=st.text(min_size=1), value=VALUES, literal=st.text(), shown=st.text())
@example(key="s.msg", value="x\u0085y", literal="x\u0085y", shown='"x\u0085y"')
@example(key="s.v", value=-0.0, literal="\u2028\u2029\ufeff\r", shown="-0.0")
@example(key="s.v", value=1e300, literal="\x00\x07\x1b", shown="1e300")
def test_values_and_model_text_survive(key, value, literal, shown):
    chunks = ["import osc.helpers\n\nscenario s:\n    do serial:\n        log(", ")\n"]
    template = SceTemplate(source="s.osc", source_sha256="0" * 64, source_dir=".", scenario="s", chunks=chunks,
                           replacements=[[repr(literal)]], keys=[key], shown=[[shown]], stored=[[value]])
    document = parse_sce(template.render(7, (0,)), "/nowhere/s7.sce")
    assert list(document.assignment) == [key]
    assert _same(document.assignment[key], value)
    assert document.text.lstrip("\n") == chunks[0] + repr(literal) + chunks[1]
    assert document.index == 7


@settings(max_examples=100, deadline=None)
@given(parameters=st.dictionaries(st.text(min_size=1), st.dictionaries(st.text(min_size=1), VALUES, max_size=3),
                                  max_size=3),
       source=st.text(min_size=1), scenario=st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,20}", fullmatch=True))
def test_header_fields_and_parameter_documents_survive(parameters, source, scenario):
    model = f"scenario {scenario}:\n"
    document = parse_sce(render_sce(source, "f" * 64, "..", scenario, 0, {}, {}, model, parameters=parameters),
                         "/nowhere/x.sce")
    assert document.source == source and document.scenario == scenario
    assert document.parameters.keys() == parameters.keys()
    for name, values in parameters.items():
        assert all(_same(document.parameters[name][k], v) for k, v in values.items())


def test_a_nel_in_a_keep_value_runs_unchanged(tmp_path):
    """The issue's case end to end: scenario_variation writes it, the runtime logs exactly that string."""
    (tmp_path / "nel.osc").write_text(
        'import osc.helpers\n\nscenario nel:\n    do serial:\n        log() with:\n'
        '            keep(it.msg in ["x\u0085y", "plain"])\n', encoding="utf-8")
    made = subprocess.run([str(BIN / "scenario_variation"), "nel.osc", "-o", "out", "--store",
                           f"sqlite:///{tmp_path / 's.db'}"], cwd=tmp_path, capture_output=True, text=True)
    assert made.returncode == 0, made.stderr
    ran = subprocess.run([str(BIN / "scenario_execution"), "out/nel0.sce"], cwd=tmp_path, capture_output=True)
    assert ran.returncode == 0, ran.stderr
    assert "x\u0085y".encode() in ran.stdout
