"""The per-run ``coverage.json``: what the builder writes reads back; bad files are located errors."""

from __future__ import annotations

import json
import os

import pytest

from coverage_engine.coverage.errors import RunFileError
from coverage_engine.coverage.run_file import (
    RunCoverageBuilder,
    read_run_coverage,
    run_coverage_dict,
    write_run_coverage,
)
from coverage_engine.coverage.values import ValueType


def _builder() -> RunCoverageBuilder:
    builder = RunCoverageBuilder("cut_in", source="out/cut_in3.sce", variant="cut_in3",
                                 assignment={"cut_in.speed": 20.0, "cut_in.lane": "side!left"})
    speed = builder.cover("speed", path="cut_in", value_type="float", unit="kph", range=(0, 120), every=20,
                          text="ego speed", ignore="speed > 200")
    side = builder.cover("side", path="cut_in", value_type=ValueType("enum", ("left", "right")))
    both = builder.cross("speed_x_side", ["speed", "side"], path="cut_in")
    ttc = builder.record("min_ttc", path="cut_in", value_type="float", unit="s", event="finish")
    speed.add(57.5)
    speed.add(float("nan"))          # not a JSON value: counted as ignored
    speed.drop()                     # the ignore: condition matched once
    side.add("left")
    both.add([57.5, "left"])
    ttc.add(1.8)
    return builder


def test_what_the_builder_writes_reads_back_the_same(tmp_path):
    run = _builder().build("failed", "too close", duration=1.5)
    path = write_run_coverage(tmp_path, run)
    assert path == tmp_path / "coverage.json"
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".")]       # no temporary file left behind
    again = read_run_coverage(path)
    assert again == run
    assert run.samples[0] == [57.5] and run.ignored[0] == 2
    assert again.items[2].items == ("speed", "side") and again.items[2].full_name == "cut_in.speed_x_side"
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert doc["run"] == {"scenario": "cut_in", "verdict": "failed", "source": "out/cut_in3.sce",
                          "variant": "cut_in3", "reason": "too close", "duration": 1.5,
                          "assignment": {"cut_in.speed": 20.0, "cut_in.lane": "side!left"}}
    assert doc["items"][0] == {"name": "speed", "kind": "cover", "path": "cut_in", "type": "float", "unit": "kph",
                               "range": [0, 120], "every": 20, "ignore": "speed > 200", "event": "end",
                               "text": "ego speed", "ignored": 2, "samples": [57.5]}
    assert run_coverage_dict(again) == doc


def test_writing_replaces_a_link_instead_of_following_it(tmp_path):
    victim = tmp_path / "elsewhere.json"
    victim.write_text("keep me", encoding="utf-8")
    (tmp_path / "out").mkdir()
    os.symlink(victim, tmp_path / "out" / "coverage.json")
    write_run_coverage(tmp_path / "out" / "coverage.json", _builder().build("passed"))
    assert victim.read_text(encoding="utf-8") == "keep me"
    assert not os.path.islink(tmp_path / "out" / "coverage.json")


def test_the_builder_refuses_a_sample_of_the_wrong_type():
    builder = RunCoverageBuilder("s")
    builder.cover("mode", value_type=ValueType("enum", ("a", "b"))).add("c")
    with pytest.raises(RunFileError, match=r"items\[0\]\.samples\[0\]: 'c' is not a enum \[a, b\] value"):
        builder.build("passed")


BAD_FILES = [
    ("{\n  \"format\": 1,,\n}", "2:15", "not valid JSON: Expecting property name enclosed in double quotes"),
    ('{"format": "scenario-coverage/run", "format_version": 3, "run": {}}', "1:55",
     "format_version: format_version 3 is not read by this release (it reads 1 and 2)"),
    ('{"format": "scenario-coverage/run", "format_version": 1,\n "run": {"scenario": "s", "verdict": "won"}}',
     "2:38", "run.verdict: must be one of passed, failed, error, skipped"),
    ('{"format": "scenario-coverage/run", "format_version": 1, "run": {"scenario": "s", "verdict": "passed"},\n'
     ' "items": [{"name": "v", "kind": "cover", "type": "float", "range": [0, 100], "every": 0.001}]}',
     "2:88", "items[0].every: [0..100] every 0.001 makes 100000 buckets; at most 10000"),
    ('{"format": "scenario-coverage/run", "format_version": 1, "run": {"scenario": "s", "verdict": "passed"},\n'
     ' "items": [{"name": "x", "kind": "cover", "items": ["a", "b"]}]}',
     "2:53", "items[0].items[0]: no item 'a' at path '' in this file"),
    ('{"format": "scenario-coverage/run", "format_version": 1, "run": {"scenario": "s", "verdict": "passed"},\n'
     ' "items": [{"name": "n", "kind": "cover", "type": "int", "range": [1, 5], "every": 1.5}]}',
     "2:84", "items[0].every: an int item's buckets hold whole numbers: 'every' must be whole"),
    ('{"format": "scenario-coverage/run", "format_version": 1, "run": {"scenario": "s", "verdict": "passed"},\n'
     ' "items": [{"name": "b", "kind": "cover", "type": "bool", "samples": [true, 1]}]}',
     "2:77", "items[0].samples[1]: 1 is not a bool value"),
    ('{"format": "scenario-coverage/run", "format_version": 1, "run": {"scenario": "s", "verdict": "passed"},\n'
     ' "items": [{"name": "b", "kind": "cover", "type": "bool"}, {"name": "b", "kind": "record", "type": "int"}]}',
     "2:69", "items[1].name: item 'b' is declared twice (first as items[0])"),
]


@pytest.mark.parametrize(("text", "where", "message"), BAD_FILES)
def test_a_bad_file_is_an_error_at_the_bad_value(tmp_path, text, where, message):
    path = tmp_path / "coverage.json"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(RunFileError) as caught:
        read_run_coverage(path)
    assert str(caught.value) == f"{path}:{where}: error: {message}"


def test_size_is_bounded(tmp_path):
    path = tmp_path / "coverage.json"
    path.write_text(" " * 2048, encoding="utf-8")
    with pytest.raises(RunFileError, match="larger than 1024 bytes"):
        read_run_coverage(path, max_bytes=1024)
