"""The .sce format: what is written reads back, line numbers agree, bad files get clear errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from coverage_engine.errors import SceFormatError
from coverage_engine.files.sce import SCE_FORMAT_VERSION, parse_sce, read_sce
from coverage_engine.files.sce_writer import SceTemplate, relative_source_dir, render_sce

OSC = """import osc.helpers

scenario test:
    do serial:
        log() with:
            keep(it.msg == 'x')
"""


def _write(tmp_path: Path, text: str, name: str = "main0.sce") -> Path:
    path = tmp_path / "out" / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def test_round_trip_fields(tmp_path):
    text = render_sce("main.osc", "a" * 64, "..", "test", 3, {"test.log.msg": "x"}, {"test.log.msg": "'x'"}, OSC)
    doc = read_sce(_write(tmp_path, text))
    assert doc.format_version == SCE_FORMAT_VERSION
    assert doc.source == "main.osc"
    assert doc.source_sha256 == "a" * 64
    assert doc.scenario == "test"
    assert doc.index == 3
    assert doc.assignment == {"test.log.msg": "x"}
    assert doc.source_dir == str(tmp_path.resolve())
    assert doc.text.lstrip("\n") == OSC
    assert doc.parameters is None


def test_header_comment_per_varied_parameter():
    text = render_sce("main.osc", "0" * 64, ".", "test", 0, {"test.a": 1, "test.b": "s"},
                      {"test.a": "1", "test.b": '"s"'}, OSC)
    lines = text.splitlines()
    assert lines[0].startswith(f"# scenario_variation .sce, format {SCE_FORMAT_VERSION}")
    assert lines[1] == "# test.a = 1"
    assert lines[2] == '# test.b = "s"'


def test_model_lines_keep_their_sce_line_numbers(tmp_path):
    text = render_sce("main.osc", "0" * 64, ".", "test", 0, {}, {}, OSC)
    doc = parse_sce(text, str(tmp_path / "x.sce"))
    sce_lines = text.splitlines()
    for number, line in enumerate(doc.text.splitlines(), start=1):
        if line:
            assert sce_lines[number - 1] == "  " + line


@pytest.mark.parametrize("model", ["  indented first\n\tx\n", "no final newline", "a\r\nb\n", "ctl \x01 x\n",
                                   "snow ☃ man\n", "\n\nblank start\n", "trailing   \n   \n"])
def test_any_text_survives(model, tmp_path):
    text = render_sce("m.osc", "0" * 64, ".", "", 0, {}, {}, model)
    assert parse_sce(text, str(tmp_path / "m0.sce")).text.endswith(model.rstrip("\n") + "\n")


def test_parameters_document_is_kept(tmp_path):
    text = render_sce("m.osc", "0" * 64, ".", "test", 0, {}, {}, OSC, parameters={"test": {"v": 2}})
    doc = parse_sce(text, str(tmp_path / "m0.sce"))
    assert doc.parameters == {"test": {"v": 2}}
    assert doc.assignment == {"parameter_document": 0}


def test_template_renders_choices():
    chunks = ["scenario a:\n    do log() with:\n        keep(", ")\n"]
    template = SceTemplate(source="a.osc", source_sha256="0" * 64, source_dir=".", scenario="a", chunks=chunks,
                           replacements=[["it.msg == 'x'", "it.msg == 'y'"]], keys=["a.log.msg"],
                           shown=[["'x'", "'y'"]], stored=[["x", "y"]])
    doc = parse_sce(template.render(1, (1,)), "/tmp/a1.sce")
    assert doc.assignment == {"a.log.msg": "y"}
    assert "keep(it.msg == 'y')" in doc.text


def test_size_is_small_for_a_library_import():
    assert len(render_sce("main.osc", "0" * 64, "..", "test", 0, {"test.log.msg": "x"},
                          {"test.log.msg": "'x'"}, OSC).encode()) < 2048


def test_unknown_version(tmp_path):
    text = render_sce("m.osc", "0" * 64, ".", "test", 0, {}, {}, OSC).replace(
        f"format_version: {SCE_FORMAT_VERSION}", "format_version: 99")
    with pytest.raises(SceFormatError, match="unsupported .sce format version 99"):
        read_sce(_write(tmp_path, text))


@pytest.mark.parametrize("text, message", [
    ("- a\n- b\n", "expected a YAML mapping"),
    ("model: x\n", "'format_version' is missing"),
    ("format_version: 1\nmodel: x\n", "'source' is missing"),
    ("key: [unclosed\n", "not a valid .sce file"),
])
def test_malformed(tmp_path, text, message):
    with pytest.raises(SceFormatError, match=message) as info:
        read_sce(_write(tmp_path, text))
    assert info.value.location is None or info.value.location.file.endswith("main0.sce")


def test_wrong_type(tmp_path):
    text = render_sce("m.osc", "0" * 64, ".", "test", 0, {}, {}, OSC).replace('scenario: "test"', "scenario: [1]")
    with pytest.raises(SceFormatError, match="'scenario' must be a str"):
        read_sce(_write(tmp_path, text))


def test_missing_file(tmp_path):
    with pytest.raises(SceFormatError, match="no such file"):
        read_sce(tmp_path / "nope.sce")


def test_relative_source_dir(tmp_path):
    assert relative_source_dir(tmp_path, tmp_path / "out") == ".."
    assert relative_source_dir(tmp_path / "a", tmp_path / "b" / "c") == "../../a"


def test_scenario_not_in_the_model_is_an_error(tmp_path):
    text = render_sce("m.osc", "0" * 64, ".", "test", 0, {}, {}, OSC).replace('scenario: "test"', 'scenario: "nosuch"')
    with pytest.raises(SceFormatError, match=r"scenario 'nosuch' is not declared in its model \(scenarios there: test\)"
                       ) as info:
        read_sce(_write(tmp_path, text))
    assert info.value.location.line == text.splitlines().index('scenario: "nosuch"') + 1


@pytest.mark.parametrize("cut", ["  import osc.helpers\n\n  scenario test:\n", 'source_dir: "."\n', "\n  scenario te"])
def test_truncated_file_is_reported_as_truncated(tmp_path, cut):
    text = render_sce("m.osc", "0" * 64, ".", "test", 0, {"test.log.msg": "x"}, {"test.log.msg": "'x'"}, OSC)
    assert text.endswith("\n# end of .sce\n")
    short = text[:text.index(cut) + len(cut)]
    with pytest.raises(SceFormatError, match="truncated .sce file") as info:
        read_sce(_write(tmp_path, short))
    assert info.value.location.line == short.rstrip("\n").count("\n") + 1


def test_version_1_without_end_line_is_still_read(tmp_path):
    text = render_sce("m.osc", "0" * 64, ".", "test", 0, {}, {}, OSC)
    old = text.replace(f"format {SCE_FORMAT_VERSION}:", "format 1:").replace(
        f"format_version: {SCE_FORMAT_VERSION}", "format_version: 1").replace("# end of .sce\n", "")
    doc = read_sce(_write(tmp_path, old))
    assert doc.format_version == 1 and doc.scenario == "test" and "keep(it.msg == 'x')" in doc.text


def test_source_sha256_is_provenance_only(tmp_path):
    """A later change of the .osc (another SHA-256) does not change what the .sce runs: it has its own model."""
    text = render_sce("m.osc", "f" * 64, ".", "test", 0, {}, {}, OSC)
    doc = read_sce(_write(tmp_path, text))
    assert doc.source_sha256 == "f" * 64 and doc.text.lstrip("\n") == OSC
