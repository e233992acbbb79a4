"""The JUnit files of a real batch as CI tools read them (issue 19): Jenkins' schema and junitparser.

Variants made by the real ``scenario_variation`` run through the real ``scenario_batch_execution``,
each job the real ``scenario_execution`` (behind a small shell wrapper that makes some jobs exit
non-zero after a passing run, or crash before writing anything). The batch has passing, failing,
erroring, timed-out and (in a second run with ``--halt-on-failure``) skipped jobs.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from batch_fixtures import cli_env, run_cli
from junitparser import Error, Failure, JUnitXml, Skipped
from tests_schema import assert_valid

BIN = Path(sys.executable).parent

CUT = """import osc.helpers

scenario cut_in:
    mode: string = "ok0"
    keep(mode in ["ok0", "fail", "exitcode", "crash", "ok4", "ok5", "ok6", "ok7", "ok8", "ok9", "ok10"])
    do serial:
        log(mode)
        check: compare(left_value: mode, operator: "!=", right_value: "fail")
        emit end
"""

SLOW = """import osc.helpers

scenario slow:
    gap: time = 1s
    keep(gap in [60s])
    do serial:
        log("waiting")
        wait elapsed(gap)
"""

#: cut2 passes but its process exits 3; cut3 dies before writing anything; the others run as they are.
WRAPPER = f"""
case "$0" in
  */cut3.sce) echo "crashing before the run"; exit 4 ;;
  */cut2.sce) "{BIN / 'scenario_execution'}" "$0" --output-dir "$1"; exit 3 ;;
esac
exec "{BIN / 'scenario_execution'}" "$0" --output-dir "$1"
"""

NAMES = [f"cut{i}" for i in range(11)] + ["slow0"]


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    """Variation, then two batches over the same 12 variants: -j 2 with a timeout, and -j 1 halting."""
    root = tmp_path_factory.mktemp("ci")
    (root / "cut.osc").write_text(CUT)
    (root / "slow.osc").write_text(SLOW)
    env = cli_env(root)
    for source, out in (("cut.osc", "v1"), ("slow.osc", "v2")):
        made = subprocess.run([str(BIN / "scenario_variation"), source, "-o", out], cwd=root, env=env,
                              capture_output=True, text=True)
        assert made.returncode == 0, made.stdout + made.stderr
    (root / "in").mkdir()
    for sce in [*(root / "v1").glob("*.sce"), *(root / "v2").glob("*.sce")]:
        shutil.copy(sce, root / "in" / sce.name)
    command = ["--", "sh", "-c", WRAPPER, "{SCENARIO}", "{OUTPUT_DIR}"]
    first = run_cli(["-i", "in", "-o", "res", "-j", "2", "--timeout", "12", "--grace", "2", *command], root, env)
    halted = run_cli(["-i", "in", "-o", "halted", "--halt-on-failure", *command], root, env)
    return root, first, halted


def _cases(path: Path):
    """``[(suite name, testcase)]`` of a merged report, read by junitparser."""
    report = JUnitXml.fromfile(str(path))
    return [(suite.name, case) for suite in report for case in suite]


def test_every_file_validates_against_the_schema(batch):
    root, first, halted = batch
    assert first.returncode == 1 and halted.returncode == 1
    files = [root / "res/test.xml", root / "halted/test.xml", *sorted(root.glob("res/*/test.xml"))]
    assert len(files) == 2 + len(NAMES) - 1              # cut3 crashed before writing its own
    for path in files:
        assert_valid(path)


def test_one_testcase_per_job_in_natural_order_with_names_and_reasons(batch):
    root, first, _ = batch
    cases = _cases(root / "res/test.xml")
    assert [suite for suite, _ in cases] == NAMES        # cut2 before cut10, one testcase each
    by_suite = {suite: case for suite, case in cases}
    assert by_suite["cut4"].name == "cut4[mode=ok4]" and by_suite["cut4"].classname == "cut.cut_in"
    assert by_suite["slow0"].name == "slow0[gap=60s]" and by_suite["slow0"].classname == "slow.slow"
    assert all(len(name) <= 120 for name in (case.name for _, case in cases))

    def problem(name):
        results = by_suite[name].result
        assert len(results) == 1, name
        return results[0]

    failed = problem("cut1")
    assert isinstance(failed, Failure) and re.fullmatch(
        r"'check' at .*cut\.osc:8:9 \(.*cut1\.sce:\d+:9\) failed: 'fail' != 'fail' is False", failed.message)
    exit_code = problem("cut2")
    assert isinstance(exit_code, Error) and exit_code.type == "exit-code"
    assert exit_code.message == "exit code 3 although its test.xml passed"
    crashed = problem("cut3")
    assert isinstance(crashed, Error) and crashed.message == "no test.xml written (exit code 4)"
    timed_out = problem("slow0")
    assert isinstance(timed_out, Error) and timed_out.type == "timeout"
    assert timed_out.message == "timed out after 12 s"
    for name, kind in (("cut1", "'check'"), ("cut2", "exit code 3"), ("cut3", "no test.xml"),
                       ("slow0", "timed out")):
        result = problem(name)
        assert result.text.startswith(result.message), name          # GitLab shows only the text
        assert kind in result.text
    assert "crashing before the run" in by_suite["cut3"].system_out      # the end of log.txt
    assert "waiting" in by_suite["slow0"].system_out
    assert all(not by_suite[n].result and not by_suite[n].system_out for n in NAMES if n.startswith("cut")
               and n not in ("cut1", "cut2", "cut3"))
    report = JUnitXml.fromfile(str(root / "res/test.xml"))
    report.update_statistics()
    assert (report.tests, report.failures, report.errors) == (12, 1, 3)


def test_per_run_files_are_named_after_their_variant(batch):
    root, _, _ = batch
    for name in NAMES:
        if name == "cut3":
            continue
        report = JUnitXml.fromfile(str(root / "res" / name / "test.xml"))
        [(suite, case)] = [(s, c) for s in report for c in s]
        assert suite.name == name and case.name.startswith(f"{name}[")
    aborted = JUnitXml.fromfile(str(root / "res/slow0/test.xml"))
    [case] = [c for s in aborted for c in s]
    assert case.result[0].message.startswith("aborted by SIGTERM while 'wait' at ")


def test_halted_jobs_are_skipped_testcases_and_progress_is_in_natural_order(batch):
    root, _, halted = batch
    cases = _cases(root / "halted/test.xml")
    assert [suite for suite, _ in cases] == NAMES
    outcomes = {suite: type(case.result[0]).__name__ if case.result else "passed" for suite, case in cases}
    assert outcomes["cut0"] == "passed" and outcomes["cut1"] == "Failure"
    assert all(outcomes[n] == "Skipped" for n in NAMES[2:])
    assert all(isinstance(case.result[0], Skipped) and case.name.startswith(suite + "[")
               for suite, case in cases[2:])
    lines = [line.split()[2] for line in halted.stdout.splitlines() if re.match(r"\[\d+/12\]", line)]
    assert lines == ["cut0", "cut1"]


def test_progress_lines_follow_natural_order(tmp_path):
    root = tmp_path
    (root / "in").mkdir()
    for i in (10, 2, 1, 0, 11):
        (root / "in" / f"v{i}.sce").write_text("x\n")
    done = run_cli(["-i", "in", "-o", "res", "--", "sh", "-c",
                    'echo "<testsuite><testcase name=\\"t\\"/></testsuite>" > "$1/test.xml"', "{SCENARIO}",
                    "{OUTPUT_DIR}"], root, cli_env(root))
    assert done.returncode == 0, done.stdout + done.stderr
    order = [line.split()[2] for line in done.stdout.splitlines() if line.startswith("[")]
    assert order == ["v0", "v1", "v2", "v10", "v11"]
