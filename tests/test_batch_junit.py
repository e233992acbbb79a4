"""The merged JUnit report: totals, names, properties, schema, and robustness against any child XML."""

from __future__ import annotations

import xml.etree.ElementTree as ET

from hypothesis import given, settings
from hypothesis import strategies as st
from tests_schema import assert_valid

from coverage_engine.results.atomic import write_text_atomically
from executor.batch.junit_merge import merged_report
from store.jobs import Job
from store.states import JobState
from store.variant_lookup import VariantInfo

OUTCOME_TAG = {"failure": "<failure message='f'/>", "error": "<error message='e'/>",
               "skipped": "<skipped/>", "passed": "",
               # bare tags, as some tools write them, still count
               "bare_failure": "<failure/>", "bare_error": "<error/>"}


def _job(name: str, status: JobState, xml: str | None, seq: int = 0, exit_code: int | None = 0,
         reason: str | None = None) -> Job:
    return Job(id=seq + 1, batch_id=1, seq=seq, name=name, scenario_path=f"/in/{name}.sce", scenario_sha="0",
               status=status, attempts=1, exit_code=exit_code, reason=reason, duration=1.5, junit_xml=xml,
               log_tail="last words of the log")


def _child_xml(outcomes: list[str]) -> str:
    cases = "".join(f"<testcase classname='c' name='t{i}' time='0.5'>{OUTCOME_TAG[o]}</testcase>"
                    for i, o in enumerate(outcomes))
    return f"<testsuites><testsuite name='x' tests='999' failures='999'>{cases}</testsuite></testsuites>"


def _root(text: str) -> ET.Element:
    return ET.fromstring(text.encode())


def test_one_testcase_per_job_whatever_happened_to_it():
    jobs = [
        _job("none", JobState.ERROR, None, 0, reason="no test.xml written (exit code 0)"),
        _job("slow", JobState.TIMEOUT, _child_xml(["failure"]), 1, exit_code=143, reason="timed out after 2 s"),
        _job("rc", JobState.ERROR, _child_xml(["passed"]), 2, exit_code=3,
             reason="exit code 3 although its test.xml passed"),
        _job("left_out", JobState.CANCELLED, None, 3),
        _job("queued", JobState.QUEUED, None, 4),
    ]
    text = merged_report(jobs, {"/in/rc.sce": VariantInfo({"sc.speed": 3}, "sc", "/src/drive.osc")})
    assert_valid(text)
    root = _root(text)
    suites = {s.get("name"): s for s in root.iter("testsuite")}
    assert list(suites) == ["none", "slow", "rc"]
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("3", "0", "3")
    assert float(root.get("time")) == 1.5 + 1.5 + 0.5      # job durations where the child gave none or timed out
    error = suites["none"].find("testcase/error")
    assert error.get("message") == "no test.xml written (exit code 0)"
    assert error.text.startswith(error.get("message")) and "last words" in suites["none"].find(
        "testcase/system-out").text
    slow = suites["slow"].findall("testcase")
    assert len(slow) == 1 and slow[0].find("error").get("type") == "timeout"
    assert slow[0].find("error").get("message") == "timed out after 2 s"
    assert slow[0].find("failure") is None
    rc_cases = suites["rc"].findall("testcase")
    assert [(c.get("classname"), c.get("name")) for c in rc_cases] == [("drive.sc", "rc[speed=3]")]
    assert rc_cases[0].find("error").get("type") == "exit-code"
    props = {p.get("name"): p.get("value") for p in suites["rc"].iter("property")}
    assert props["variation.sc.speed"] == "3" and props["exit_code"] == "3" and props["testcase"] == "t0"


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(st.sampled_from(sorted(OUTCOME_TAG)), min_size=1, max_size=4), min_size=1, max_size=6))
def test_totals_are_sums_of_the_testcases(children):
    jobs = [_job(f"j{i}", JobState.PASSED, _child_xml(outcomes), i) for i, outcomes in enumerate(children)]
    text = merged_report(jobs)
    assert_valid(text)
    root = _root(text)
    flat = [o for outcomes in children for o in outcomes]
    assert int(root.get("tests")) == len(flat)
    assert int(root.get("failures")) == flat.count("failure") + flat.count("bare_failure")
    assert int(root.get("errors")) == flat.count("error") + flat.count("bare_error")
    assert abs(float(root.get("time")) - 0.5 * len(flat)) < 1e-6
    for suite, outcomes in zip(list(root.iter("testsuite")), children, strict=True):
        assert int(suite.get("tests")) == len(outcomes)
        names = [c.get("name") for c in suite.iter("testcase")]
        assert names == ([suite.get("name")] if len(outcomes) == 1 else [f"t{i}" for i in range(len(outcomes))])


@settings(max_examples=80, deadline=None)
@given(st.text(max_size=200))
def test_any_child_xml_never_breaks_the_merge(text):
    jobs = [_job("weird", JobState.ERROR, text, reason="unreadable"), _job("ok", JobState.PASSED,
                                                                         _child_xml(["passed"]), 1)]
    root = _root(merged_report(jobs))
    assert [s.get("name") for s in root.iter("testsuite")] == ["weird", "ok"]


def test_entity_expansion_is_refused_and_report_written_atomically(tmp_path):
    bomb = ('<?xml version="1.0"?><!DOCTYPE x [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;">]>'
            '<testsuite><testcase name="&b;"/></testsuite>')
    text = merged_report([_job("bomb", JobState.ERROR, bomb, reason="unreadable")])
    assert "aaaaaaaaaa" not in text
    target = tmp_path / "out" / "test.xml"
    target.parent.mkdir()
    target.write_text("old")
    write_text_atomically(target, text)
    assert _root(target.read_text()).get("errors") == "1"
    assert [p.name for p in target.parent.iterdir()] == ["test.xml"]


def test_times_and_timestamps_fit_the_schema():
    child = ("<testsuites><testsuite name='x'><testcase classname='c' name='t' time='1e-05' "
             "timestamp='2026-11-22T07:20:00'/><testcase name='u' time='-3'/></testsuite></testsuites>")
    job = Job(id=1, batch_id=1, seq=0, name="ts", scenario_path="/in/ts.osc", scenario_sha="0",
              status=JobState.PASSED, attempts=1, exit_code=0, started_at=1_700_000_000.0, duration=1.0, junit_xml=child)
    text = merged_report([job])
    assert_valid(text)
    root = _root(text)
    assert [c.get("time") for c in root.iter("testcase")] == ["0.000010", "0.000000"]
    assert [c.get("timestamp") for c in root.iter("testcase")] == [None, None]
    assert root.find("testsuite").get("timestamp").startswith("2023-11-1")


def test_a_variant_is_looked_up_under_every_spelling_of_its_path(tmp_path, monkeypatch):
    """As given, absolute, and with links resolved: through a linked folder, a linked file, and a ``..``
    after a link (resolved after the link, as the system does), each folder resolved once."""
    import os

    from store.variant_lookup import _candidates

    deep = tmp_path / "real" / "deep"
    (deep / "sub").mkdir(parents=True)
    (deep / "f.sce").write_text("x")
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "t.sce").write_text("x")
    (tmp_path / "real" / "filelink.sce").symlink_to(tmp_path / "other" / "t.sce")
    (tmp_path / "link").symlink_to(deep / "sub")
    (tmp_path / "deeplink").symlink_to(deep)
    monkeypatch.chdir(tmp_path)
    for path in ("link/../f.sce", "deeplink/f.sce", "deeplink/../filelink.sce", "real/filelink.sce",
                 "missing/none.sce", str(tmp_path / "real" / "deep" / "f.sce")):
        names = _candidates(path, {})
        assert {path, os.path.abspath(path), os.path.realpath(path)} == names, path
