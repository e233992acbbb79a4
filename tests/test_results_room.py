"""The results room (coverage_engine.results): one reader, one verdict word per outcome, one atomic writer,
and each result file name and scenario suffix defined once."""

from __future__ import annotations

import ast
import os
import stat
from pathlib import Path

import pytest

from coverage_engine.results.atomic import write_text_atomically
from coverage_engine.results.read import JunitUnreadable, iter_suites, read_cases
from coverage_engine.results.verdicts import FAILING, VERDICT_OF_STATE, Verdict, run_verdict
from store.states import FINAL, JobState

ROOT = Path(__file__).resolve().parent.parent

TWO_SUITES = """<testsuites>
  <testsuite name="a"><properties><property name="status" value="failed"/></properties>
    <testcase classname="c" name="one" time="0.5"/>
    <testcase classname="c" name="two" time="x"><failure message="too close" type="assert">gap 1m</failure></testcase>
  </testsuite>
  <testsuite name="b"><testcase classname="c" name="three"><skipped message="not run"/></testcase></testsuite>
</testsuites>"""


def test_the_whole_and_the_streamed_reading_give_the_same_testcases(tmp_path):
    report = tmp_path / "test.xml"
    report.write_text(TWO_SUITES)
    streamed = [case for suite in iter_suites(report) for case in suite.cases]
    assert streamed == read_cases(TWO_SUITES)
    assert [(c.name, c.outcome, c.message, c.type, c.time) for c in streamed] == [
        ("one", "passed", None, None, 0.5), ("two", "failure", "too close", "assert", None),
        ("three", "skipped", "not run", None, None)]
    assert [s.properties for s in iter_suites(report)] == [{"status": "failed"}, {}]


@pytest.mark.parametrize(("cases", "verdict", "reason"), [
    ('<testcase name="a"/><testcase name="b"><failure message="f"/></testcase>'
     '<testcase name="c"><error type="crash"/></testcase>', Verdict.ERROR, "f"),
    ('<testcase name="a"/><testcase name="b"><failure/></testcase>', Verdict.FAILED, "failed"),
    ('<testcase name="a"><skipped/></testcase>', Verdict.SKIPPED, None),
    ('<testcase name="a"/><testcase name="b"><skipped/></testcase>', Verdict.PASSED, None),
    ("", Verdict.ERROR, "test.xml has no testcase"),
])
def test_a_runs_verdict_is_folded_from_its_testcases(tmp_path, cases, verdict, reason):
    report = tmp_path / "test.xml"
    report.write_text(f'<testsuite tests="99" failures="0">{cases}</testsuite>')
    assert run_verdict(report) == (verdict, reason)


def test_an_unreadable_report_is_one_error_with_one_exception(tmp_path):
    report = tmp_path / "test.xml"
    report.write_text('<testsuite><testcase name="broken"')
    verdict, reason = run_verdict(report)
    assert verdict is Verdict.ERROR and reason.startswith("test.xml: not well-formed XML")
    with pytest.raises(JunitUnreadable, match="not well-formed"):
        read_cases(report.read_text())
    with pytest.raises(JunitUnreadable, match="expected <testsuites> or <testsuite>"):
        read_cases("<html/>")
    bomb = '<!DOCTYPE x [<!ENTITY a "aaaa">]><testsuite><testcase name="&a;"/></testsuite>'
    with pytest.raises(JunitUnreadable):
        read_cases(bomb)


def test_entities_are_refused_with_or_without_a_document_type_and_a_plain_declaration_reads_alike():
    plain = '<testsuite><testcase name="a &amp; b" classname="c"><failure message="&#233;"/></testcase></testsuite>'
    declared = '<?xml version="1.0"?><!DOCTYPE testsuite>' + plain
    assert read_cases(plain) == read_cases(declared)
    assert read_cases(plain)[0].name == "a & b" and read_cases(plain)[0].message == "\u00e9"
    with pytest.raises(JunitUnreadable, match="not well-formed"):       # no declaration: no entity to use
        read_cases('<testsuite><testcase name="&a;"/></testsuite>')
    external = ('<?xml version="1.0"?><!DOCTYPE x [<!ENTITY e SYSTEM "file:///etc/passwd">]>'
                '<testsuite><testcase name="&e;"/></testsuite>')
    with pytest.raises(JunitUnreadable):
        read_cases(external)
    with pytest.raises(TypeError):            # bytes could spell the declaration in another encoding
        read_cases(declared.encode("utf-16"))
    with pytest.raises(JunitUnreadable, match="not well-formed"):       # XML spells the declaration in capitals
        read_cases('<!doctype x [<!ENTITY a "aaaa">]><testsuite><testcase name="&a;"/></testsuite>')


def test_every_job_state_has_a_verdict_and_only_final_ones_are_finished():
    assert set(VERDICT_OF_STATE) == {state.value for state in JobState}
    for state in JobState:
        verdict = VERDICT_OF_STATE[state.value]
        assert (verdict is Verdict.PENDING) == (state in (JobState.QUEUED, JobState.RUNNING))
    assert {VERDICT_OF_STATE[state.value] for state in FINAL} == {Verdict.PASSED, *FAILING}
    assert f"{Verdict.FAILED}" == "failed" and "failed" in FAILING


@pytest.mark.parametrize("durable", [True, False])
def test_the_atomic_writer_replaces_a_link_and_leaves_no_temporary_file(tmp_path, durable):
    secret = tmp_path / "secret"
    secret.write_text("keep")
    out = tmp_path / "out"
    out.mkdir()
    (out / "test.xml").symlink_to(secret)
    old = os.umask(0o027)
    try:
        import importlib

        import coverage_engine.results.atomic as atomic
        atomic = importlib.reload(atomic)          # the umask is read once, at import
        atomic.write_text_atomically(out / "test.xml", "<testsuites/>", durable=durable)
    finally:
        os.umask(old)
        importlib.reload(atomic)
    assert secret.read_text() == "keep"
    assert not (out / "test.xml").is_symlink() and (out / "test.xml").read_text() == "<testsuites/>"
    assert stat.S_IMODE((out / "test.xml").stat().st_mode) == 0o640
    assert sorted(p.name for p in out.iterdir()) == ["test.xml"]


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary_file(tmp_path):
    target = tmp_path / "coverage.json"
    target.write_text("old")
    with pytest.raises(TypeError):
        write_text_atomically(target, None)      # type: ignore[arg-type]
    assert target.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["coverage.json"]


#: What must be defined once: result file names (coverage_engine/results/files.py) and scenario suffixes
#: (coverage_engine/suffixes.py).
_ONCE = {"test.xml", "log.txt", "coverage.json", "declared.json", ".osc", ".sce"}
_HOMES = {ROOT / "coverage_engine" / "results" / "files.py", ROOT / "coverage_engine" / "suffixes.py"}


def _docstrings(tree: ast.AST) -> set[int]:
    found = set()
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(body[0].value, ast.Constant):
            found.add(id(body[0].value))
    return found


def test_result_file_names_and_scenario_suffixes_are_each_defined_once():
    copies = []
    for package in ("cli", "executor", "store", "coverage_engine"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if path in _HOMES:
                continue
            tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
            docs = _docstrings(tree)
            copies += [f"{path.relative_to(ROOT)}:{node.lineno}: {node.value!r}" for node in ast.walk(tree)
                       if isinstance(node, ast.Constant) and node.value in _ONCE and id(node) not in docs]
    assert copies == []


def test_a_document_read_again_gives_equal_cases_that_callers_may_change_alone():
    """A batch reads each job's report twice (judging, then merging): the second read is a lookup, and
    its list is the caller's own."""
    first = read_cases(TWO_SUITES)
    first.clear()
    again = read_cases(TWO_SUITES)
    assert [case.name for case in again] == ["one", "two", "three"]
    assert again == read_cases(TWO_SUITES) and again is not read_cases(TWO_SUITES)


def test_the_documents_kept_for_a_second_read_stay_within_their_bound():
    from coverage_engine.results.read import _Recent

    recent = _Recent(limit=100)
    recent.keep("a" * 60, ())
    recent.keep("b" * 30, ())
    assert recent.get("a" * 60) == () and recent.get("b" * 30) == ()
    recent.keep("c" * 20, ())                       # over the bound: it starts again
    assert recent.get("a" * 60) is None and recent.get("c" * 20) == ()
    recent.keep("d" * 101, ())                      # larger than the bound: never kept
    assert recent.get("d" * 101) is None and recent.get("c" * 20) == ()
