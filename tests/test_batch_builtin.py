"""The built-in runner (no launch command; issue 14) through the real CLI, and no orphans after kill -9.

The scenarios are the probe variants of :mod:`probe_variants`: the tests see where user code ran and
whether one job's state reached the next.
"""

from __future__ import annotations

import json
import os
import re
import signal
import sqlite3
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from batch_fixtures import alive, cli_env, marked, run_cli, server_of, start_cli, wait_until_unmarked
from probe_variants import make_variants, records
from tests_schema import assert_valid

from executor.batch.hand_over import CLAIM_CHUNK

pytest_plugins = ["batch_stores"]            # the pg_url fixture

BIN = Path(sys.executable).parent

def _normal(xml_text: str) -> bytes:
    """A report without what may differ between two runs: times, host, output folder."""
    root = ET.fromstring(xml_text.encode())
    for element in root.iter():
        for key in ("time", "timestamp", "hostname"):
            element.attrib.pop(key, None)
        if element.tag == "property" and element.get("name") in ("output_dir", "host"):
            element.set("value", "-")
    return ET.tostring(root)


def cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


# -j 1 on a machine with a core to spare: each job goes to a spare child the server forked ahead and
# warmed up on its own probe; -j 2 (on 2 cores): each job is forked when it is asked for.
@pytest.mark.parametrize("slots", ["1", "2"], ids=["spare", "forked"])
def test_builtin_and_launched_runs_give_the_same_results(tmp_path, slots):
    if slots == "1" and cores() < 2:
        pytest.skip("a warm spare needs a second core")
    names = [f"n{i}" for i in range(48)] + ["fail", "crash"]
    env = make_variants(tmp_path, names)
    (tmp_path / "tmp").mkdir()
    env["TMPDIR"] = str(tmp_path / "tmp")
    builtin = run_cli(["-i", "out", "-o", "builtin", "-j", slots], tmp_path, env)
    assert list((tmp_path / "tmp").iterdir()) == []            # nothing of a probe run is left behind
    launched = run_cli(["-i", "out", "-o", "launched", "-j", "2", "--", str(BIN / "scenario_execution"),
                        "{SCENARIO}", "--output-dir", "{OUTPUT_DIR}"], tmp_path, env)
    assert builtin.returncode == launched.returncode == 1, builtin.stdout + builtin.stderr
    merged = (tmp_path / "builtin/test.xml").read_text()
    assert_valid(merged)
    assert _normal(merged) == _normal((tmp_path / "launched/test.xml").read_text())
    root = ET.fromstring(merged.encode())
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("50", "1", "1")
    crashed = root.find(".//testsuite[@name='job49']/testcase/error")
    assert crashed.get("message").startswith("no test.xml written (killed by SIGSEGV)")
    for index in range(50):
        one, other = tmp_path / "builtin" / f"job{index}", tmp_path / "launched" / f"job{index}"
        assert sorted(p.name for p in one.iterdir()) == sorted(p.name for p in other.iterdir())
        assert (one / "log.txt").read_bytes() == (other / "log.txt").read_bytes(), index
        if (one / "test.xml").exists():
            assert _normal((one / "test.xml").read_text()) == _normal((other / "test.xml").read_text())
        if index < 49:                                         # the crashed job wrote none
            ours, theirs = (json.loads((folder / "coverage.json").read_text()) for folder in (one, other))
            for run in (ours["run"], theirs["run"]):
                run.pop("duration")
            assert ours == theirs and ours["run"]["assignment"] == {"job.name": names[index]}, index
    # user code ran in each job, never in the parent: imported there, called once, saw no other job's state
    ledger = records(tmp_path)
    assert len(ledger) == 100
    for name, pid, _parent, imported_in, calls, leaked in ledger:
        assert imported_in == pid and calls == "1" and leaked == "-", (name, pid, imported_in, calls, leaked)
    forked = ledger[:50]
    parents = {row[2] for row in forked}
    assert len(parents) == 1 and all(not alive(int(p)) for p in parents)   # one fork server, gone at the end


def test_builtin_timeout_retries_post_run_and_a_hanging_job(tmp_path):
    env = make_variants(tmp_path, ["a", "hang", "b"])
    hook = tmp_path / "hook.sh"
    hook.write_text('#!/bin/sh\necho "hook $1" >> "$BATCH_LEDGER.hooks"\n')
    hook.chmod(0o755)
    start = time.monotonic()
    done = run_cli(["-i", "out", "-o", "res", "-j", "2", "--timeout", "3", "--grace", "0.5", "--retries", "1",
                    "--post-run", str(hook)], tmp_path, env)
    assert time.monotonic() - start < 30
    assert done.returncode == 1, done.stdout + done.stderr
    root = ET.parse(tmp_path / "res/test.xml").getroot()
    errors = root.findall(".//error")
    assert [e.get("type") for e in errors] == ["timeout"] and errors[0].get("message") == "timed out after 3 s"
    by_name = {}
    for name, *_ in records(tmp_path):
        by_name[name] = by_name.get(name, 0) + 1
    assert by_name == {"a": 1, "hang": 2, "b": 1}                 # the timeout was retried once
    hooks = (tmp_path / "ledger.txt.hooks").read_text().splitlines()
    assert sorted(hooks) == sorted(f"hook {tmp_path / 'res' / f'job{i}'}" for i in (0, 1, 1, 2))
    assert (tmp_path / "res/job1/log.1.txt").exists()             # the first attempt's log is kept


def test_builtin_shard_and_resume_need_no_command(tmp_path):
    names = [f"s{i}" for i in range(8)]
    env = make_variants(tmp_path, names)
    first = run_cli(["-i", "out", "-o", "one", "--shard", "1/2"], tmp_path, env)
    second = run_cli(["-i", "out", "-o", "two", "--shard", "2/2"], tmp_path, env)
    assert first.returncode == second.returncode == 0, first.stdout + first.stderr
    suites = [s.get("name") for path in ("one", "two") for s in ET.parse(tmp_path / path / "test.xml").iter(
        "testsuite")]
    assert sorted(suites) == sorted(f"job{i}" for i in range(8))
    again = run_cli(["-o", "one", "--resume"], tmp_path, env)
    assert again.returncode == 0 and len(records(tmp_path)) == 8       # nothing ran twice


def _worker_id(store: Path) -> str:
    with sqlite3.connect(store) as conn:
        row = conn.execute("SELECT worker_id FROM jobs WHERE worker_id IS NOT NULL LIMIT 1").fetchone()
    return row[0]


@pytest.mark.parametrize(("launched", "slots"), [(False, "2"), (False, "1"), (True, "2")],
                         ids=["builtin", "builtin-spare", "launched"])
def test_kill_9_of_the_runner_leaves_no_process_and_resume_finishes(tmp_path, launched, slots):
    names = [f"k{i}" for i in range(40)]
    env = make_variants(tmp_path, names, pause=0.3)
    scratch = tmp_path / "tmp"                       # the runner's temporary folders go here
    scratch.mkdir()
    env["TMPDIR"] = str(scratch)
    command = ["--", str(BIN / "scenario_execution"), "{SCENARIO}", "--output-dir", "{OUTPUT_DIR}"] if launched \
        else []
    runner = start_cli(["-i", "out", "-o", "res", "-j", slots, *command], tmp_path, env)
    deadline = time.monotonic() + 60
    while len(records(tmp_path)) < (6 if slots == "2" else 3):
        assert time.monotonic() < deadline and runner.poll() is None, runner.stdout.read()
        time.sleep(0.02)
    mark = f"SCENARIO_BATCH_RUNNER={_worker_id(tmp_path / '.scenario_store.db')}"
    # both slots can end their jobs at the same moment (same pause, started together), and a launched
    # child carries the mark only once it has exec'd: wait for the next marked process, do not sample once
    while not marked(mark):
        assert time.monotonic() < deadline and runner.poll() is None, "the batch's processes carry the mark"
        time.sleep(0.01)
    assert launched or any(scratch.iterdir()), "the fork server's scratch folder is where TMPDIR says"
    runner.send_signal(signal.SIGKILL)
    runner.communicate(timeout=10)
    killed_at = time.monotonic()
    wait_until_unmarked(mark, killed_at, 3)
    while any(scratch.iterdir()):                    # and so are the runner's temporary folders
        assert time.monotonic() - killed_at < 5, f"left behind: {sorted(p.name for p in scratch.iterdir())}"
        time.sleep(0.05)
    finished = _finished_jobs(tmp_path)
    assert 0 < len(finished) < 40

    resumed = run_cli(["-o", "res", "--resume", "-j", "2"], tmp_path, env, timeout=120)
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    suites = [s.get("name") for s in ET.parse(tmp_path / "res/test.xml").iter("testsuite")]
    assert suites == [f"job{i}" for i in range(40)]                  # every job has one result, in order
    runs: dict[str, int] = {}
    for name, *_ in records(tmp_path):
        runs[name] = runs.get(name, 0) + 1
    assert set(runs) == set(names)
    assert all(runs[f"k{int(job[3:])}"] == 1 for job in finished), "a finished job ran again"


@pytest.mark.parametrize(("slots", "count", "pause"), [(2, 30, 0.3), (1, 6, 1.0)], ids=["loop", "threads"])
def test_jobs_waiting_at_a_fork_server_that_died_run_on_the_next_one(tmp_path, slots, count, pause):
    """The fork server is killed while it runs jobs and holds more for the next free slots: the running
    ones end as errors, the ones it held never ran, so they go back to the queue and run on a new server.
    (At -j 1 each job waits for the server in a thread of its own, the job's output shown as it runs,
    and one job waits: the kill comes in the middle of a job, when the next one has long been waiting.)"""
    names = [f"s{i:02}" for i in range(count)]
    env = make_variants(tmp_path, names, pause=pause)
    runner = start_cli(["-i", "out", "-o", "res", "-j", str(slots)], tmp_path, env)
    deadline = time.monotonic() + 60
    while len(records(tmp_path)) < slots or server_of(runner.pid) is None:
        assert time.monotonic() < deadline and runner.poll() is None, runner.stdout.read()
        time.sleep(0.02)
    time.sleep(pause / 2)                                # the next jobs are under way, the ones after wait
    server = server_of(runner.pid)
    assert server is not None
    os.kill(server, signal.SIGKILL)
    out = runner.communicate(timeout=120)[0]
    with sqlite3.connect(tmp_path / ".scenario_store.db") as conn:
        ends = conn.execute("SELECT name, status, reason, attempts FROM jobs ORDER BY seq").fetchall()
    errors = [(name, reason) for name, status, reason, _attempts in ends if status == "error"]
    assert any(attempts > 1 for _name, status, _reason, attempts in ends if status == "passed"), \
        (ends, out)                                      # a job went back, and passed on the next server
    # only the jobs it was running: its slots, and one more when it had just forked the next job of a
    # slot whose end it had not yet told (a job that had passed, its end then lost with the server)
    assert len(ends) == count and len(errors) <= slots + 1, (errors, out)
    assert all("SIGKILL" in (reason or "") for _name, reason in errors), errors
    assert all(status in ("passed", "error") for _name, status, _reason, _attempts in ends), ends
    assert runner.returncode == (1 if errors else 0), out
    ran = [row[0] for row in records(tmp_path)]
    assert sorted(set(ran)) == sorted(ran) and len(ran) >= count - len(errors), ran   # none ran twice


def _finished_jobs(root: Path) -> set[str]:
    """Jobs with a verdict in the store (a resume must not run them again)."""
    with sqlite3.connect(root / ".scenario_store.db") as conn:
        rows = conn.execute("SELECT name FROM jobs WHERE status IN ('passed', 'failed', 'error', 'timeout')")
        return {row[0] for row in rows}


def test_worker_subcommand_runs_builtin_batches_from_postgresql(pg_url, tmp_path):
    env = make_variants(tmp_path, [f"w{i}" for i in range(6)])
    enqueued = run_cli(["-i", "out", "-o", "res", "--store", pg_url, "--enqueue-only"], tmp_path, env)
    assert enqueued.returncode == 0, enqueued.stdout + enqueued.stderr
    workers = [start_cli(["worker", "--store", pg_url, "-j", "2", "--poll", "0.1"], tmp_path, env) for _ in range(2)]
    for worker in workers:
        out = worker.communicate(timeout=120)[0]
        assert worker.returncode == 0, out
    report = run_cli(["report", "--store", pg_url, "-o", "merged.xml"], tmp_path, env)
    assert report.returncode == 0, report.stdout + report.stderr
    assert_valid(tmp_path / "merged.xml")
    assert sorted(row[0] for row in records(tmp_path)) == sorted(f"w{i}" for i in range(6))


def test_ctrl_c_stops_builtin_jobs_and_resume_finishes(tmp_path):
    env = make_variants(tmp_path, [f"c{i}" for i in range(6)], pause=1.0)
    runner = start_cli(["-i", "out", "-o", "res", "-j", "2"], tmp_path, env)
    deadline = time.monotonic() + 60

    def executing(job: str) -> bool:
        log = tmp_path / f"res/{job}/log.txt"
        return log.exists() and "Executing" in log.read_text()

    # both running jobs have started their scenario (job0's log is read below): wait for that state
    while not (executing("job0") and executing("job1")):
        assert time.monotonic() < deadline and runner.poll() is None
        time.sleep(0.02)
    runner.send_signal(signal.SIGINT)
    out = runner.communicate(timeout=30)[0]
    assert runner.returncode == 130, out
    root = ET.parse(tmp_path / "res/test.xml").getroot()
    assert root.get("tests") == "6" and root.find(".//error[@type='cancelled']") is not None
    log = (tmp_path / "res/job0/log.txt").read_text()
    assert "aborted by SIGINT" in log                               # the job's own handler ran, as launched
    # job2 to job5 were handed to the fork server ahead, waiting for a slot: withdrawn, never run, back in
    # the queue (only the two that ran were cancelled), and their folders are gone again
    assert records(tmp_path) == [] and sorted(p.name for p in (tmp_path / "res").iterdir() if p.is_dir()) == [
        "job0", "job1"]
    assert "6 job(s): 4 queued, 2 cancelled;" in out and "cancelled before it started" not in out, out
    resumed = run_cli(["-o", "res", "--resume", "-j", "2"], tmp_path, env, timeout=120)
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert os.path.exists(tmp_path / "res/job5/test.xml")
    assert sorted(row[0] for row in records(tmp_path)) == [f"c{i}" for i in range(6)]    # each once


def test_jobs_start_in_the_order_they_were_claimed(tmp_path):
    """Each job's thread hands its start to the fork server, ahead of a free slot; the threads race,
    yet the jobs start in order (the server forks them in the order their requests come: pids rise)."""
    names = [f"o{i:02}" for i in range(40)]
    env = make_variants(tmp_path, names, pause=0.05)
    done = run_cli(["-i", "out", "-o", "res", "-j", "2"], tmp_path, env)
    assert done.returncode == 0, done.stdout + done.stderr
    pid_of = {row[0]: int(row[1]) for row in records(tmp_path)}
    pids = [pid_of[name] for name in names]
    assert pids == sorted(pids), list(zip(names, pids, strict=True))


def _most_running(store: Path, process: subprocess.Popen) -> int:
    """The most jobs the store showed ``running`` at once while ``process`` ran (sampled)."""
    most = 0
    while process.poll() is None:
        try:                                       # read-only: the runner makes the store
            with sqlite3.connect(f"file:{store}?mode=ro", uri=True) as conn:
                running = conn.execute("SELECT COUNT(*) FROM jobs WHERE status = 'running'").fetchone()[0]
            most = max(most, running)
        except sqlite3.OperationalError:           # not made yet, or busy
            pass
        time.sleep(0.01)
    return most


def test_only_the_single_host_run_holds_jobs_ahead(tmp_path):
    """The single-host run claims a chunk of jobs at once (all 8 here: fewer than ``CLAIM_CHUNK``), held
    until a slot frees; a ``worker``, even of one batch, claims no more than its slots, leaving the rest
    to other hosts. With ``--post-run`` hooks the chunk is claimed too, but no job is handed to the fork
    server ahead (the next job waits for the hooks: see the hooks' tests)."""
    assert CLAIM_CHUNK >= 8
    env = make_variants(tmp_path, [f"h{i}" for i in range(8)], pause=0.2)
    store = tmp_path / "queue.db"
    local = start_cli(["-i", "out", "-o", "one", "-j", "1", "--store", f"sqlite:///{store}"], tmp_path, env)
    assert _most_running(store, local) == 8 and local.returncode == 0
    enqueued = run_cli(["-i", "out", "-o", "two", "--store", f"sqlite:///{store}", "--enqueue-only"], tmp_path, env)
    assert enqueued.returncode == 0, enqueued.stdout + enqueued.stderr
    worker = start_cli(["worker", "--store", f"sqlite:///{store}", "--batch", "2", "-j", "1", "--poll", "0.1"],
                       tmp_path, env)
    assert _most_running(store, worker) == 1 and worker.returncode == 0
    hooked = start_cli(["-i", "out", "-o", "three", "-j", "1", "--store", f"sqlite:///{store}",
                        "--post-run", f"{sys.executable} -c pass"], tmp_path, env)   # the next job waits for hooks
    assert _most_running(store, hooked) == 8 and hooked.returncode == 0
    assert len(records(tmp_path)) == 24


def test_a_job_handed_over_ahead_is_timed_from_its_start(tmp_path):
    """The fork server holds the next job until the slot is free; its timeout and time start then."""
    # Each job pauses 3 s: one timed from its hand-over (a pause earlier) would run past the 5.5 s timeout,
    # while a job timed from its start has 2.5 s to spare for a slow machine's start-up.
    env = make_variants(tmp_path, ["a", "b", "c"], pause=3.0)
    done = run_cli(["-i", "out", "-o", "res", "-j", "1", "--timeout", "5.5"], tmp_path, env)
    assert done.returncode == 0, done.stdout + done.stderr           # none waited into a timeout
    assert sorted(row[0] for row in records(tmp_path)) == ["a", "b", "c"]
    finished = [line for line in done.stdout.splitlines() if re.match(r"\[\d+/3\] passed ", line)]
    durations = [float(line.split()[-2]) for line in finished]           # "[1/3] passed    job0  3.05 s"
    assert len(durations) == 3 and all(2.9 < t < 5.5 for t in durations), done.stdout   # not the wait


# A module of the scenario's folder named like one the standard library has (and the entry-point lookup
# loads), a job that leaves a thread running when its scenario ends, and one killed after writing to both
# streams: what the interpreter does at start and at its end must be what the forked job does.
INTERPRETER_MODULE = '''
import os, signal, sys, threading, time

def act(name):
    if name == "thread":
        def late():
            time.sleep(0.3)
            fd = os.open(os.environ["BATCH_LEDGER"], os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
            os.write(fd, b"thread ended\\n")
            os.close(fd)
        threading.Thread(target=late).start()
    if name == "killed":
        print("out before the kill")
        sys.stderr.write("err before the kill\\n")
        print("out again")
        os.kill(os.getpid(), signal.SIGKILL)
    return "the scenario folder's calendar"
'''


@pytest.mark.parametrize("unbuffered", [True, False], ids=["unbuffered", "buffered"])
def test_builtin_jobs_start_and_end_as_a_fresh_interpreter(tmp_path, unbuffered):
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "calendar.py").write_text(INTERPRETER_MODULE)
    (tmp_path / "src" / "job.osc").write_text("""import osc.helpers

struct folder:
    def act(name: string) -> string is external calendar.act()

scenario job:
    name: string = "x"
    keep(name in ["plain", "thread", "killed"])
    do serial:
        log(folder.act(name))
""")
    env = cli_env(tmp_path)
    if not unbuffered:
        env.pop("PYTHONUNBUFFERED")
    made = subprocess.run([str(BIN / "scenario_variation"), "src/job.osc", "-o", "out"], cwd=tmp_path, env=env,
                          capture_output=True, text=True)
    assert made.returncode == 0, made.stdout + made.stderr
    builtin = run_cli(["-i", "out", "-o", "builtin", "-j", "2"], tmp_path, env)
    launched = run_cli(["-i", "out", "-o", "launched", "-j", "2", "--", str(BIN / "scenario_execution"),
                        "{SCENARIO}", "--output-dir", "{OUTPUT_DIR}"], tmp_path, env)
    assert builtin.returncode == launched.returncode == 1, builtin.stdout + builtin.stderr
    logs = {}
    for job in ("job0", "job1", "job2"):
        one, other = (tmp_path / runner / job / "log.txt" for runner in ("builtin", "launched"))
        assert one.is_file() and other.is_file(), (job, sorted(os.listdir(tmp_path / "builtin")),
                                                   builtin.stdout + builtin.stderr, launched.stdout)
        logs[job] = one.read_text()
        assert one.read_bytes() == other.read_bytes(), job
    assert "the scenario folder's calendar" in logs["job0"]          # its own module, not the library's
    assert (tmp_path / "ledger.txt").read_text() == "thread ended\n" * 2   # the job waited for its thread
    killed = logs["job2"]
    assert "err before the kill" in killed
    assert ("out before the kill" in killed) is unbuffered           # nothing written is lost, unbuffered
    if unbuffered:
        assert killed.index("out before") < killed.index("err before") < killed.index("out again")


SPAN_MODULE = '''
import os, time

def span(name):
    began = time.time()
    time.sleep(0.15)
    line = "%s %.6f %.6f\\n" % (name, began, time.time())
    fd = os.open(os.environ["BATCH_LEDGER"], os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    os.write(fd, line.encode())
    os.close(fd)
    return name
'''


@pytest.mark.parametrize("launched", [False, True], ids=["builtin", "launched"])
def test_never_more_jobs_at_once_than_slots(tmp_path, launched):
    """-j 2: two jobs run side by side, and at no moment three (12 jobs of 0.15 s each)."""
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "span_mod.py").write_text(SPAN_MODULE)
    names = ", ".join(f'"s{i}"' for i in range(12))
    (tmp_path / "src" / "job.osc").write_text(f"""import osc.helpers

struct spans:
    def span(name: string) -> string is external span_mod.span()

scenario job:
    name: string = "x"
    keep(name in [{names}])
    do serial:
        log(spans.span(name))
""")
    env = cli_env(tmp_path)
    made = subprocess.run([str(BIN / "scenario_variation"), "src/job.osc", "-o", "out"], cwd=tmp_path, env=env,
                          capture_output=True, text=True)
    assert made.returncode == 0, made.stdout + made.stderr
    command = ["--", str(BIN / "scenario_execution"), "{SCENARIO}", "--output-dir", "{OUTPUT_DIR}"] if launched \
        else []
    done = run_cli(["-i", "out", "-o", "res", "-j", "2", *command], tmp_path, env)
    assert done.returncode == 0, done.stdout + done.stderr
    events = []
    for _name, began, ended in (line.split() for line in (tmp_path / "ledger.txt").read_text().splitlines()):
        events += [(float(began), 1), (float(ended), -1)]
    assert len(events) == 24
    running = most = 0
    for _at, step in sorted(events):
        running += step
        most = max(most, running)
    assert most == 2


def test_the_fork_server_makes_a_jobs_folder_and_refuses_one_planted_as_a_link(tmp_path):
    """A built-in job's folder and log are made by the fork server as the job starts (not by the batch
    process); a folder planted as a link is refused there as the batch process refused it: the job is
    an error that says so, nothing is written through the link, the other jobs run."""
    env = make_variants(tmp_path, ["p0", "p1", "p2"])
    victim = tmp_path / "victim"
    victim.mkdir()
    (tmp_path / "res").mkdir()
    (tmp_path / "res" / "job1").symlink_to(victim)
    done = run_cli(["-i", "out", "-o", "res", "-j", "2"], tmp_path, env)
    assert done.returncode == 1, done.stdout + done.stderr
    assert list(victim.iterdir()) == []
    errors = {c.get("name"): c.find("error") for c in ET.parse(tmp_path / "res/test.xml").getroot().iter("testcase")}
    refused = [e for e in errors.values() if e is not None]
    assert len(refused) == 1 and refused[0].get("message", "").startswith("cannot prepare the job: the job folder")
    assert "symbolic link" in refused[0].get("message", "")
    assert sorted(row[0] for row in records(tmp_path)) == ["p0", "p2"]
    assert all((tmp_path / f"res/job{i}/log.txt").is_file() for i in (0, 2))
