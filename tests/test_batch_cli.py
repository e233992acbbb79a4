"""The batch command through its real console script, with real children and a real SQLite store."""

from __future__ import annotations

import os
import re
import sqlite3
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from batch_fixtures import child_command, cli_env, ledger, run_cli, start_cli, write_child, write_scenarios


def _suites(path: Path) -> dict[str, ET.Element]:
    root = ET.parse(path).getroot()
    assert root.tag == "testsuites"
    return {s.get("name"): s for s in root.iter("testsuite")}


def _props(suite: ET.Element) -> dict[str, str]:
    return {p.get("name"): p.get("value") for p in suite.iter("property")}


def _batch(tmp_path: Path, specs: dict[str, str], *options: str, env=None, timeout=120):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", specs)
    return run_cli(["-i", "in", "-o", "results", *options, "--", *child_command(child)], tmp_path,
                   env=env or cli_env(tmp_path), timeout=timeout)


def test_seed_command_line_verdicts_and_merged_report(tmp_path):
    result = _batch(tmp_path, {"a_ok": "print=hello-a", "b_fail": "xml=fail\nexit=1", "c_ok": ""})
    assert result.returncode == 1, result.stdout + result.stderr
    assert "hello-a" in result.stdout                      # -j 1 shows the child's output live
    assert result.stdout.index("start a_ok") < result.stdout.index("start b_fail") < result.stdout.index(
        "start c_ok")
    root = ET.parse(tmp_path / "results" / "test.xml").getroot()
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("3", "1", "0")
    assert [c.get("name") for c in root.iter("testcase")] == ["a_ok", "b_fail", "c_ok"]
    suites = _suites(tmp_path / "results" / "test.xml")
    assert list(suites) == ["a_ok", "b_fail", "c_ok"]
    props = _props(suites["b_fail"])
    assert props["scenario_file"] == str((tmp_path / "in" / "b_fail.sce").resolve())
    assert props["attempts"] == "1" and props["exit_code"] == "1" and props["testcase"] == "sc"
    failure = suites["b_fail"].find("testcase/failure")
    assert failure is not None and failure.get("message") == "it failed"
    for name in ("a_ok", "b_fail", "c_ok"):
        assert (tmp_path / "results" / name / "test.xml").exists()
        assert f"start {name}" in (tmp_path / "results" / name / "log.txt").read_text()


def test_all_passed_exit_zero_and_osc_files_too(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"x1": ""}, suffix=".osc")
    write_scenarios(tmp_path / "in", {"x2": ""}, suffix=".sce")
    (tmp_path / "in" / "notes.txt").write_text("not a scenario")
    result = run_cli(["-i", "in", "-o", "deep/results", "-j", "auto", "--", *child_command(child)], tmp_path)
    assert result.returncode == 0, result.stderr
    assert list(_suites(tmp_path / "deep/results/test.xml")) == ["x1", "x2"]


@pytest.mark.slow
def test_user_errors_are_one_line_without_traceback(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"a": ""})
    (tmp_path / "empty").mkdir()
    cases = [
        ["-i", "in", "-o", "r", "--", sys.executable, str(child), "{SCENARIO}"],          # no {OUTPUT_DIR}
        ["-i", "in", "-o", "r", "--", sys.executable, str(child), "in/a.sce", "x"],       # no placeholders
        ["-i", "empty", "-o", "r", "--", *child_command(child)],                          # no scenario files
        ["-i", "missing", "-o", "r", "--", *child_command(child)],
        ["-i", "in", "-o", "r", "--shard", "3/2", "--", *child_command(child)],
        ["-i", "in", "-o", "r", "-j", "zero", "--", *child_command(child)],
        ["-i", "in", "-o", "r", "--bogus", "--", *child_command(child)],
        ["-i", "in", "-o", "r", "--", "no-such-program-xyz", "{SCENARIO}", "{OUTPUT_DIR}"],
        ["-o", "r", "--resume", "--", *child_command(child)],                             # nothing to resume
    ]
    for args in cases:
        result = run_cli(args, tmp_path)
        assert result.returncode != 0, args
        assert "Traceback" not in result.stderr + result.stdout, args
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and "error" in lines[0], (args, result.stderr)
    assert not (tmp_path / "ledger.txt").exists()        # nothing ran


def test_exit_codes_usage_2_runtime_1(tmp_path):
    """A malformed command line exits 2 (docs/batch.md); what depends on files, PATH or the store exits 1."""
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"a": ""})
    (tmp_path / "empty").mkdir()
    (tmp_path / "afile").write_text("")
    cmd = child_command(child)
    usage = [
        ["-i", "in", "-o", "r", "--", sys.executable, str(child), "{SCENARIO}"],          # no {OUTPUT_DIR}
        ["-i", "in", "-o", "r", "--", sys.executable, str(child), "{OUTPUT_DIR}"],        # no {SCENARIO}
        ["-o", "r", "--", *cmd],                                                          # no -i
        ["-i", "in", "-o", "r", "--shard", "0/3", "--", *cmd],
        ["-i", "in", "-o", "r", "--shard", "x", "--", *cmd],
        ["-i", "in", "-o", "r", "-j", "0", "--", *cmd],
        ["-i", "in", "-o", "r", "--bogus", "--", *cmd],
        ["-i", "in", "-o", "r", "--post-run", "", "--", *cmd],
        ["-o", "r", "--resume", "--", "true", "no-placeholders"],
    ]
    for option in ("--timeout", "--grace", "--lease"):
        for value in ("nan", "inf", "-inf", "0", "-1", "soon", "1e308", "31536001"):
            usage.append(["-i", "in", "-o", "r", option, value, "--", *cmd])
    for option in ("--lease", "--poll"):
        for value in ("nan", "inf", "0"):
            usage.append(["worker", option, value])
    runtime = [
        ["-i", "empty", "-o", "r", "--", *cmd],                                           # no scenario files
        ["-i", "missing", "-o", "r", "--", *cmd],
        ["-i", "in", "-o", "r", "--", "no-such-program-xyz", "{SCENARIO}", "{OUTPUT_DIR}"],
        ["-i", "in", "-o", "afile/r", "--", *cmd],
        ["-o", "nothing_here", "--resume"],
    ]
    for args, code in [(a, 2) for a in usage] + [(a, 1) for a in runtime]:
        result = run_cli(args, tmp_path)
        assert result.returncode == code, (args, result.returncode, result.stderr)
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and "error" in lines[0] and "Traceback" not in lines[0], (args, result.stderr)
    assert not (tmp_path / "ledger.txt").exists()        # nothing ran
    assert "afile is not a folder" in run_cli(runtime[3], tmp_path).stderr


def test_an_endless_timeout_is_bounded_to_a_year(tmp_path):
    result = _batch(tmp_path, {"a": ""}, "--timeout", "1e308")
    assert result.returncode == 2
    assert result.stderr.strip().endswith("Invalid value for '--timeout': must be at most 31536000 s (got 1e308)")


def test_non_finite_timeout_is_refused_not_applied(tmp_path):
    result = _batch(tmp_path, {"a": ""}, "--timeout", "nan")
    assert result.returncode == 2
    assert "--timeout" in result.stderr and "finite" in result.stderr
    assert "timed out" not in result.stdout and not (tmp_path / "results" / "test.xml").exists()


def test_report_into_a_path_under_a_file_says_so(tmp_path):
    env = cli_env(tmp_path)
    assert _batch(tmp_path, {"a": ""}, env=env).returncode == 0
    (tmp_path / "afile").write_text("keep me")
    store = f"sqlite:///{tmp_path / '.scenario_store.db'}"
    result = run_cli(["report", "--store", store, "-o", "afile/x.xml"], tmp_path, env)
    assert result.returncode == 1
    assert result.stderr.strip() == f"scenario_batch_execution: error: cannot write the report: " \
                                    f"{tmp_path / 'afile'} is not a folder"
    assert (tmp_path / "afile").read_text() == "keep me"
    nested = run_cli(["report", "--store", store, "-o", "afile/deeper/x.xml"], tmp_path, env)
    assert nested.returncode == 1 and "afile is not a folder" in nested.stderr
    fine = run_cli(["report", "--store", store, "-o", "new/dir/x.xml"], tmp_path, env)
    assert fine.returncode == 0 and (tmp_path / "new/dir/x.xml").exists()


def test_missing_garbage_empty_xml_and_big_output(tmp_path):
    result = _batch(tmp_path, {"big": "output_mb=50", "garbage": "xml=garbage", "empty": "xml=empty",
                               "none": "xml=none", "two": "xml=two"}, "-j", "3")
    assert result.returncode == 1
    suites = _suites(tmp_path / "results" / "test.xml")
    assert list(suites) == ["big", "empty", "garbage", "none", "two"]
    assert _props(suites["big"])["status"] == "passed"
    assert (tmp_path / "results/big/log.txt").stat().st_size > 50 * 1024 * 1024
    for name in ("garbage", "none", "empty"):
        suite = suites[name]
        assert (suite.get("tests"), suite.get("errors")) == ("1", "1"), name
        error = suite.find("testcase/error")
        assert "exit code 0" in error.get("message") and error.text.startswith(error.get("message"))
        assert f"start {name}" in suite.find("testcase/system-out").text
    assert [c.get("name") for c in suites["two"].iter("testcase")] == ["first", "second"]
    assert suites["two"].get("failures") == "1"
    root = ET.parse(tmp_path / "results" / "test.xml").getroot()
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("6", "1", "3")


def test_return_value_and_ignore_flag(tmp_path):
    specs = {"rc3": "exit=3"}
    assert _batch(tmp_path, specs).returncode == 1
    suite = _suites(tmp_path / "results" / "test.xml")["rc3"]
    # an exit code despite a passing test.xml is an error on that testcase, not a test failure or a new testcase
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == ("1", "0", "1")
    error = suite.find("testcase/error")
    assert error.get("type") == "exit-code" and error.get("message") == "exit code 3 although its test.xml passed"
    again = run_cli(["-i", "in", "-o", "results", "-r", "--", *child_command(tmp_path / "child.py")], tmp_path)
    assert again.returncode == 0, again.stdout


def test_timeout_kills_whole_process_group(tmp_path):
    start = time.monotonic()
    result = _batch(tmp_path, {"hangs": "grandchild=1\nhang=1", "quick": ""},
                    "--timeout", "1", "--grace", "0.5", "-j", "2")
    assert time.monotonic() - start < 20
    assert result.returncode == 1
    suite = _suites(tmp_path / "results" / "test.xml")["hangs"]
    error = suite.find("testcase/error")
    assert error.get("type") == "timeout" and _props(suite)["status"] == "timeout"
    grandchild = int((tmp_path / "results/hangs/grandchild.pid").read_text())
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        try:
            os.kill(grandchild, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        raise AssertionError("the grandchild survived the timeout")


def test_retries_only_infrastructure_errors_and_keep_logs(tmp_path):
    result = _batch(tmp_path, {"flaky": "fail_first=1", "failing": "xml=fail\nexit=1"}, "--retries", "2")
    assert result.returncode == 1
    suites = _suites(tmp_path / "results" / "test.xml")
    assert _props(suites["flaky"])["status"] == "passed" and _props(suites["flaky"])["attempts"] == "2"
    assert _props(suites["failing"])["attempts"] == "1"
    assert ledger(tmp_path) == {"flaky": 1, "failing": 1}
    assert "first attempt: no result" in (tmp_path / "results/flaky/log.1.txt").read_text()
    assert "first attempt" not in (tmp_path / "results/flaky/log.txt").read_text()


def test_post_run_hooks_run_per_job_and_failures_do_not_stop(tmp_path):
    hook = tmp_path / "hook.py"
    hook.write_text("import sys\nopen(sys.argv[1] + '/../calls.txt', 'a').write(sys.argv[1] + '\\n')\n")
    bad = tmp_path / "bad.py"
    bad.write_text("import sys\nsys.exit(4)\n")
    result = _batch(tmp_path, {"a": "", "b": ""}, "--post-run", f"{sys.executable} {hook}",
                    "--post-run", f"{sys.executable} {bad}")
    assert result.returncode == 0, result.stdout + result.stderr
    calls = (tmp_path / "results/calls.txt").read_text().splitlines()
    assert [Path(c).name for c in calls] == ["a", "b"]
    assert result.stderr.count("exit code 4") == 2


@pytest.mark.slow
def test_shards_partition_the_files(tmp_path):
    specs = {f"s{i:02d}": f"print=file {i}" for i in range(12)}
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", specs)
    seen: list[str] = []
    for index in (1, 2, 3):
        result = run_cli(["-i", "in", "-o", f"shard{index}", "--shard", f"{index}/3", "--",
                          *child_command(child)], tmp_path)
        assert result.returncode == 0, result.stderr
        names = list(_suites(tmp_path / f"shard{index}" / "test.xml"))
        again = run_cli(["-i", "in", "-o", f"again{index}", "--shard", f"{index}/3", "--",
                         *child_command(child)], tmp_path)
        assert again.returncode == 0 and list(_suites(tmp_path / f"again{index}" / "test.xml")) == names
        seen += names
        assert len(names) == 4, names                 # 12 files in 3 shards: 4 each, none left empty
    assert sorted(seen) == sorted(specs)


def test_halt_on_failure_starts_nothing_after_a_failure(tmp_path):
    result = _batch(tmp_path, {"a": "", "b": "xml=fail", "c": "", "d": ""}, "--halt-on-failure")
    assert result.returncode == 1
    assert ledger(tmp_path) == {"a": 1, "b": 1}
    report = tmp_path / "results" / "test.xml"
    suites = _suites(report)
    assert list(suites) == ["a", "b", "c", "d"]               # the test count in CI does not shrink
    for name in ("c", "d"):
        skipped = suites[name].findall("testcase/skipped")
        assert [s.get("message") for s in skipped] == ["not run: the batch halted after a failure"]
        assert _props(suites[name])["status"] == "cancelled"
    root = ET.parse(report).getroot()
    assert (root.get("tests"), root.get("failures")) == ("4", "1")
    assert sum(int(s.get("skipped", "0")) for s in suites.values()) == 2


@pytest.mark.slow
def test_log_is_written_while_the_child_runs(tmp_path):
    for jobs in ("1", "2"):
        child = write_child(tmp_path)
        write_scenarios(tmp_path / f"in{jobs}", {"slow": "print=early-line\nsleep=2"})
        proc = start_cli(["-i", f"in{jobs}", "-o", f"r{jobs}", "-j", jobs, "--", *child_command(child)],
                         tmp_path, cli_env(tmp_path))
        log = tmp_path / f"r{jobs}" / "slow" / "log.txt"
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and not (log.exists() and "early-line" in log.read_text()):
            time.sleep(0.05)
        assert proc.poll() is None, "the line must be in log.txt before the child ends"
        assert "early-line" in log.read_text()
        proc.communicate(timeout=30)
        assert proc.returncode == 0


def test_old_summary_kept_until_the_end_and_nothing_deleted(tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    (results / "test.xml").write_text('<testsuite tests="2" failures="2"/>')
    (results / "keep.me").write_text("user file")
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"slow": "sleep=2"})
    proc = start_cli(["-i", "in", "-o", "results", "--", *child_command(child)], tmp_path, cli_env(tmp_path))
    deadline = time.monotonic() + 10
    while not (results / "slow" / "log.txt").exists():          # the job is running
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.02)
    assert (results / "test.xml").read_text() == '<testsuite tests="2" failures="2"/>'
    proc.communicate(timeout=30)
    assert proc.returncode == 0
    assert list(_suites(results / "test.xml")) == ["slow"]
    assert (results / "keep.me").read_text() == "user file"


def test_variant_assignment_becomes_properties(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"v0": "", "plain": ""})
    store = tmp_path / "store.db"
    from store.database import open_engine
    from store.variants import VariantRecord, content_hash, record_variation

    engine = open_engine(f"sqlite:///{store}")               # a store as scenario_variation leaves it
    record_variation(engine, source_path="/src/v.osc", source_sha256=content_hash("scenario v:\n"),
                     source_text="scenario v:\n", options={}, output_dir=str(tmp_path / "in"),
                     records=[VariantRecord(index=0, scenario="scenario", sce_text="# v0\n",
                                            assignment={"scenario.speed": 5.0, "scenario.name": "a"},
                                            file_path=str((tmp_path / "in" / "v0.sce").resolve()))])
    engine.dispose()
    result = run_cli(["-i", "in", "-o", "results", "--store", f"sqlite:///{store}", "--",
                      *child_command(child)], tmp_path)
    assert result.returncode == 0, result.stderr
    suites = _suites(tmp_path / "results" / "test.xml")
    assert _props(suites["v0"])["variation.scenario.speed"] == "5.0"
    assert _props(suites["v0"])["variation.scenario.name"] == "a"
    assert not any(k.startswith("variation.") for k in _props(suites["plain"]))


def test_incompatible_store_is_refused(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"a": ""})
    assert run_cli(["-i", "in", "-o", "r", "--", *child_command(child)], tmp_path).returncode == 0
    conn = sqlite3.connect(tmp_path / ".scenario_store.db")
    conn.execute("UPDATE store_meta SET schema_version = 99")
    conn.commit()
    conn.close()
    result = run_cli(["-i", "in", "-o", "r", "--", *child_command(child)], tmp_path)
    assert result.returncode == 1
    assert "schema version 99" in result.stderr and "Traceback" not in result.stderr


def _on_a_terminal(tmp_path: Path, **env: str) -> bytes:
    """Run a 4-job batch (-j 2) with a pseudo-terminal as stdout; returns what the terminal received."""
    import pty
    import subprocess

    from batch_fixtures import CLI

    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {f"s{i}": "sleep=0.4" for i in range(4)})
    leader, follower = pty.openpty()
    full_env = {**cli_env(tmp_path), "TERM": "xterm-256color", "COLUMNS": "120", **env}
    full_env.pop("NO_COLOR", None)
    full_env.update(env)
    proc = subprocess.Popen([CLI, "-i", "in", "-o", "results", "-j", "2", "--", *child_command(child)],
                            cwd=tmp_path, env=full_env, stdin=follower, stdout=follower, stderr=follower)
    os.close(follower)
    output = b""
    while True:
        try:
            chunk = os.read(leader, 65536)
        except OSError:                          # the terminal closed with the last writer
            break
        if not chunk:
            break
        output += chunk
    os.close(leader)
    assert proc.wait(timeout=60) == 0, output.decode(errors="replace")
    import shutil

    shutil.rmtree(tmp_path / "results")
    (tmp_path / ".scenario_store.db").unlink()
    return output


#: SGR sequences that set a colour (foreground/background, 8, 16, 256 or true colour).
_COLOUR = re.compile(rb"\x1b\[(?:[0-9;]*;)?(?:3[0-9]|4[0-9]|9[0-7]|10[0-7])(?:;[0-9;]*)?m")
_BAR = "━".encode()


def test_no_color_keeps_the_progress_bar_and_drops_the_colours(tmp_path):
    coloured = _on_a_terminal(tmp_path)
    assert _BAR in coloured and _COLOUR.search(coloured)
    plain = _on_a_terminal(tmp_path, NO_COLOR="1")
    assert _BAR in plain and b"4/4" in plain
    assert not _COLOUR.search(plain), _COLOUR.search(plain)


def test_progress_display_only_on_a_terminal(monkeypatch):
    import pty

    from executor.batch.progress import PlainReporter, RichReporter, make_reporter, wants_rich

    leader, follower = pty.openpty()
    with os.fdopen(leader, "rb") as _, os.fdopen(follower, "w") as terminal, \
            open(os.devnull, "w") as not_terminal:
        monkeypatch.setenv("TERM", "xterm")
        assert wants_rich(terminal) and not wants_rich(not_terminal)
        monkeypatch.setattr(sys, "stdout", terminal)
        assert isinstance(make_reporter(4), RichReporter)
        assert isinstance(make_reporter(1), PlainReporter)        # -j 1 shows the children's output instead
        monkeypatch.setenv("TERM", "dumb")
        assert not wants_rich(terminal) and isinstance(make_reporter(4), PlainReporter)


def test_status_and_report_never_create_or_migrate_a_store(tmp_path):
    for command in (["status"], ["report", "-o", "r.xml"]):
        done = run_cli([*command, "--store", "sqlite:///missing.db"], tmp_path)
        assert done.returncode == 2, done.stdout + done.stderr
        assert "there is no store at" in done.stderr and str(tmp_path / "missing.db") in done.stderr
        assert not list(tmp_path.iterdir())
    other = tmp_path / "variants.db"
    with sqlite3.connect(other) as conn:        # a database of another kind: no version table
        conn.execute("CREATE TABLE unrelated (x)")
    before = other.read_bytes()
    done = run_cli(["status", "--store", f"sqlite:///{other}"], tmp_path)
    assert done.returncode == 2 and "is not a scenario store" in done.stderr
    assert other.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["variants.db"]
