"""How an attempt's files are read when it is judged (executor.batch.verdict): a file left from before the
attempt is not taken as its own, a link or a FIFO is refused without being followed or waited on, and a
new file is read from the descriptor that was opened (no second look at the path)."""

from __future__ import annotations

import os

from coverage_engine.results.files import COVERAGE_FILE, LOG_FILE, RESULT_FILE
from executor.batch.verdict import NOT_WRITTEN, FileMark, judge, read_coverage, read_result
from executor.children.process import ProcessOutcome
from store.states import JobState

PASSED = '<testsuite><testcase name="t"/></testsuite>'


def _marked(folder, name=RESULT_FILE):
    path = folder / name
    return path, FileMark.of(str(path))


def test_no_file_and_a_file_left_as_it_was_are_both_not_written(tmp_path):
    path, mark = _marked(tmp_path)
    assert read_result(str(path), mark) == (None, [], NOT_WRITTEN)
    path.write_text(PASSED)
    stale = FileMark.of(str(path))
    assert read_result(str(path), stale) == (None, [], NOT_WRITTEN)


def test_a_file_the_attempt_wrote_is_read_with_its_cases(tmp_path):
    path, mark = _marked(tmp_path)
    path.write_text(PASSED)
    text, cases, problem = read_result(str(path), mark)
    assert problem is None and text == PASSED and [case.name for case in cases] == ["t"]


def test_a_file_rewritten_by_the_attempt_counts_even_where_one_was_before(tmp_path):
    path = tmp_path / RESULT_FILE
    path.write_text(PASSED)
    mark = FileMark.of(str(path))
    replacement = tmp_path / "new.xml"
    replacement.write_text(PASSED.replace('"t"', '"u"'))
    os.replace(replacement, path)                     # another inode: a new file
    _, cases, problem = read_result(str(path), mark)
    assert problem is None and [case.name for case in cases] == ["u"]


def test_a_link_made_by_the_attempt_is_refused_and_one_left_from_before_is_not_its_own(tmp_path):
    secret = tmp_path / "secret.xml"
    secret.write_text(PASSED)
    path, mark = _marked(tmp_path)
    path.symlink_to(secret)
    text, cases, problem = read_result(str(path), mark)
    assert text is None and cases == [] and problem is not None and "symbolic link: not followed" in problem
    assert read_result(str(path), FileMark.of(str(path))) == (None, [], NOT_WRITTEN)


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    path, mark = _marked(tmp_path)
    os.mkfifo(path)
    assert read_result(str(path), mark) == (None, [], "cannot read test.xml: test.xml is not a regular file")


def test_a_coverage_file_is_read_only_when_the_attempt_wrote_it(tmp_path):
    path, mark = _marked(tmp_path, COVERAGE_FILE)
    assert read_coverage(str(path), mark) is None
    path.write_text('{"a": 1}')
    assert read_coverage(str(path), mark) == '{"a": 1}'
    assert read_coverage(str(path), FileMark.of(str(path))) is None


def test_an_earlier_log_is_kept_and_a_folder_that_cannot_be_looked_at_is_not_taken_for_an_empty_one(tmp_path):
    from pathlib import Path

    import pytest

    from executor.batch.job_run import rotate_log

    assert rotate_log(tmp_path / "new", 1) is None               # no folder yet, no log: nothing to keep
    (tmp_path / "log.txt").write_text("first")
    kept = rotate_log(tmp_path, 2)
    assert kept == tmp_path / "log.1.txt" and kept.read_text() == "first" and not (tmp_path / "log.txt").exists()
    with pytest.raises(OSError):                                 # ENAMETOOLONG: not "no log there"
        rotate_log(Path(tmp_path) / ("x" * 300), 2)


def test_the_log_tail_is_kept_with_a_verdict_that_is_shown_and_not_read_for_a_pass(tmp_path):
    """The tail goes where a job that did not pass is shown (the merged report, the failure list): a
    passing job's log is not read at all (one file less per job for the batch process)."""
    (tmp_path / LOG_FILE).write_text("last words\n")
    mark = FileMark.of(str(tmp_path / RESULT_FILE))
    (tmp_path / RESULT_FILE).write_text(PASSED)
    passed = judge(ProcessOutcome(0, 1.0, 2.0), tmp_path, mark)
    assert passed.status is JobState.PASSED and passed.log_tail is None
    erred = judge(ProcessOutcome(3, 1.0, 2.0), tmp_path, mark)
    assert erred.status is JobState.ERROR and erred.log_tail == "last words\n"
    (tmp_path / RESULT_FILE).write_text(PASSED.replace("/>", "><failure message='no'/></testcase>"))
    failed = judge(ProcessOutcome(0, 1.0, 2.0), tmp_path, mark)
    assert failed.status is JobState.FAILED and failed.log_tail == "last words\n"
