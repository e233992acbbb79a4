"""Property test: mutated parameter files and .sce texts load or fail with one of our errors (issue 11 item 4).

Never another exception, never a hang: each input is bounded in time by hypothesis' deadline.
"""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from text_mutations import mutated

from coverage_engine.errors import OscError
from coverage_engine.files.parameters import read_parameter_documents
from coverage_engine.files.sce import parse_sce
from coverage_engine.files.sce_writer import render_sce

MODEL = "import osc.helpers\nscenario s:\n    do serial:\n        log('x')\n"
SCE = [render_sce("s.osc", "0" * 64, ".", "s", i, {"s.log.msg": v}, {}, MODEL) for i, v in enumerate(["a", 2.5])]
PARAMETERS = ["s:\n  v: 2\n", "s:\n  v: 2\n---\ns:\n  v: [1, 2]\n", "a: &x {v: 1}\nb: *x\n", "---\n"]
PIECES = ["\n", ":", "-", "---", "&a", "*a", "[", "]", "{", "}", "'", '"', "\t", "\x00", "\ufeff", "!!python/object", "%"]


@settings(max_examples=150, deadline=2000, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=mutated(PARAMETERS, PIECES))
def test_parameter_files_load_or_fail_with_our_error(tmp_path, text):
    path = tmp_path / "p.yaml"
    path.write_text(text, encoding="utf-8")
    try:
        documents = read_parameter_documents(path)
    except OscError as exc:
        assert exc.message
        return
    assert documents and all(isinstance(d, dict) for d in documents)


@settings(max_examples=150, deadline=2000)
@given(text=mutated(SCE, PIECES))
def test_sce_texts_load_or_fail_with_our_error(text):
    try:
        document = parse_sce(text, "/tmp/v.sce")
    except OscError as exc:
        assert exc.message
        return
    assert document.scenario == "s"
