"""Several forking processes (issue 34): with many slots the fork server forks from warm copies of itself.

Checked here on the real fork server with two forkers (this machine's cores would give one): the
slots are shared (never more jobs at once than the limit), waiting requests start in the order
they came, a withdrawn one is answered by the dispatcher, jobs come from both forkers, and nothing
is left when the runner closes, or when a forker dies. Then a whole batch through the real CLI on a
"16-core machine" (its core count patched in the runner's process), and ``kill -9`` of that runner.
"""

from __future__ import annotations

import json
import os
import select
import signal
import socket
import sqlite3
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from batch_fixtures import alive, marked, wait_until_unmarked
from fork_jobs import Jobs, job_folder, parent_of
from probe_variants import make_variants, records
from tests_schema import assert_valid

from executor.batch.builtin_runner import SLOTS_PER_FORKER, ForkServer, forkers_for
from executor.batch.fork_dispatch import Dispatcher, Forker
from executor.batch.fork_errors import ForkServerError
from executor.batch.fork_protocol import MAX_MESSAGE, bundles, receive
from executor.children.process import kill_orphan

BIN = Path(sys.executable).parent


def state_of(pid: int) -> str:
    with open(f"/proc/{pid}/stat") as handle:
        return handle.read().rsplit(")", 1)[1].split()[0]


def wait_gone(pid: int, why: str = "", seconds: float = 10) -> None:
    """Wait until process ``pid`` has ended (a zombie counts as ended); fail with ``why`` after ``seconds``."""
    deadline = time.monotonic() + seconds
    while alive(pid):
        assert time.monotonic() < deadline, why
        time.sleep(0.05)


def children_of(pid: int) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as handle:
            return [int(child) for child in handle.read().split()]
    except OSError:
        return []


@pytest.fixture
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    return job_folder(tmp_path, monkeypatch)


def test_forkers_follow_the_slots_and_the_cores(monkeypatch):
    import executor.batch.builtin_runner as runner

    monkeypatch.setattr(runner, "usable_cpus", lambda: 16)
    assert [forkers_for(n) for n in (1, SLOTS_PER_FORKER, SLOTS_PER_FORKER + 1, 16, 64)] == [1, 1, 2, 4, 4]
    monkeypatch.setattr(runner, "usable_cpus", lambda: 2)
    assert [forkers_for(n) for n in (1, 8, 64)] == [1, 1, 1]       # few cores: the jobs are the bottleneck


def test_requests_kept_to_go_together_fit_in_as_few_messages_as_the_size_allows_in_their_order():
    requests = [json.dumps({"id": str(i), "log": "x" * 2000}).encode() for i in range(100)]
    messages = bundles(requests)
    assert bundles(requests[:1]) == [(1, requests[0])]             # one alone goes as it is
    assert all(len(message) <= MAX_MESSAGE for _count, message in messages)
    assert [count for count, _message in messages] == [32, 32, 32, 4]   # 2 KB each
    assert [len(json.loads(message)["requests"]) for _count, message in messages] == [32, 32, 32, 4]
    ids = [request["id"] for _count, message in messages for request in json.loads(message)["requests"]]
    assert ids == [str(i) for i in range(100)]
    assert [count for count, _message in bundles(requests, 16 * 1024)] == [8] * 12 + [4]


@pytest.mark.parametrize("forkers", [1, 2])
def test_requests_kept_to_go_together_wait_for_send_submitted_and_start_in_their_order(folder, forkers):
    """Kept requests reach the server only with send_submitted (or before a request sent at once); one
    withdrawn before is answered here and never reaches the server; the others start in their order."""
    server = ForkServer(limit=1, forkers=forkers).start()
    jobs = Jobs(server, folder)
    quick = str(folder / "quick.osc")
    try:
        for job in range(3):
            jobs.submit(job, quick, later=True)
        jobs.submit(3, quick, later=True)
        server.withdraw(jobs.requests[3])
        assert jobs.replies == [(3, "withdrawn", None)]
        assert not select.select([server.fileno()], [], [], 1.0)[0]   # nothing sent, nothing started
        server.send_submitted()
        jobs.submit(4, quick, later=True)
        jobs.submit(5, quick)                                      # at once: the kept one goes first
        jobs.wait_for(6)
    finally:
        server.close()
    assert jobs.events("started") == [0, 1, 2, 4, 5] and jobs.events("exited") == [0, 1, 2, 4, 5]
    assert not (folder / "out" / "j3").exists()


def test_two_forkers_share_the_slots_and_a_waiting_job_waits_for_one(folder):
    server = ForkServer(limit=3, forkers=2).start()
    jobs = Jobs(server, folder)
    try:
        for job in range(5):
            jobs.submit(job, str(folder / ("slow.osc" if job < 4 else "quick.osc")))
        jobs.submit(5, str(folder / "quick.osc"))
        server.withdraw(jobs.requests[5])                       # still waiting: the dispatcher answers
        forkers = set(children_of(server.proc.pid))
        jobs.wait_for(6)
    finally:
        server.close()
    assert jobs.events("withdrawn") == [5]
    started = jobs.events("started")
    first_end = next(i for i, reply in enumerate(jobs.replies) if reply[1] == "exited")
    # the first three came first and started at once; the others waited for a slot (two forkers may
    # answer in either order: the replies of two processes cross)
    assert set(started[:3]) == {0, 1, 2} and sorted(started[3:]) == [3, 4]
    assert all(jobs.replies.index((job, "started", pid)) > first_end
               for job, event, pid in jobs.replies if event == "started" and job in (3, 4))
    assert sorted(jobs.events("exited")) == [0, 1, 2, 3, 4]
    running = most = 0
    for _job, event, _pid in jobs.replies:
        running += {"started": 1, "exited": -1}.get(event, 0)
        most = max(most, running)
    assert most == 3                                            # the limit holds over both forkers
    assert set(jobs.parents.values()) == forkers and len(forkers) == 2   # each forked some, the server none
    assert all(jobs.parents[job] in forkers for job in (0, 1, 2))
    assert all(not alive(pid) for pid in forkers)
    assert all((folder / "out" / f"j{job}" / "test.xml").is_file() for job in range(5))
    assert list((folder / "tmp").iterdir()) == []               # the scratch folder went with the server


def dispatched_within(dispatcher: Dispatcher, seconds: float) -> bool:
    """The dispatcher's hand-over of what waits, run in a thread: True if it returned True within ``seconds``."""
    result: list[bool] = []
    thread = threading.Thread(target=lambda: result.append(dispatcher._dispatch()), daemon=True)
    thread.start()
    thread.join(seconds)
    return result == [True]


def test_the_dispatcher_never_waits_for_a_forker_whose_socket_is_full():
    # a forker busy reaping a burst of ends reads no requests, and sends notes the dispatcher must read:
    # waiting to send to it would stop both (found in review: -j 900 on 8 cores hung)
    runner, server_end = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    forker_end, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    dispatcher = Dispatcher(server_end, limit=0)
    dispatcher.forkers.append(Forker(os.getpid(), forker_end))
    environment = {"BIG": "x" * 8192}
    for number in range(500):
        dispatcher.waiting[str(number)] = ({"id": str(number), "argv": ["scenario_execution"], "env": environment}, [])
    assert dispatched_within(dispatcher, 10)                    # returns, with requests left waiting
    forker = dispatcher.forkers[0]
    assert forker.full and 0 < forker.running < 500 and len(dispatcher.waiting) == 500 - forker.running
    assert next(iter(dispatcher.waiting)) == str(forker.running)            # the next in line, kept first
    received = []
    theirs.setblocking(False)
    while len(received) < 500:
        try:
            received.append(receive(theirs)[0]["id"])
        except BlockingIOError:
            forker.full = False                                 # (the loop does this once select says so)
            assert dispatched_within(dispatcher, 10)
    assert received == [str(number) for number in range(500)]  # every request once, in order
    for sock in (runner, server_end, forker_end, theirs):
        sock.close()


def test_a_job_waited_for_in_a_thread_gets_its_output_descriptor_through_the_dispatcher(folder):
    server = ForkServer(limit=2, forkers=2).start()
    try:
        processes = []
        for job in range(3):                 # (a job with --post-run hooks waits for its child in a thread)
            with open(folder / f"output{job}.txt", "wb") as output:
                processes.append(server.spawn(["scenario_execution", str(folder / "quick.osc"), "--output-dir",
                                               str(folder / "out" / f"t{job}")], cwd=str(folder), environment={},
                                              output_fd=output.fileno()))
        assert [process.wait(60) for process in processes] == [0, 0, 0]
    finally:
        server.close()
    assert all("Scenario 'quick' succeeded" in (folder / f"output{job}.txt").read_text() for job in range(3))


def test_a_forker_that_dies_ends_the_server_and_its_jobs(folder):
    server = ForkServer(limit=2, forkers=2).start()
    jobs = Jobs(server, folder)
    try:
        jobs.submit(0, str(folder / "hang.osc"))
        jobs.submit(1, str(folder / "hang.osc"))
        jobs.wait_for_starts(2)
        started = {job: pid for job, event, pid in jobs.replies if event == "started"}
        assert jobs.parents[0] != jobs.parents[1]               # one job on each forker
        os.kill(jobs.parents[0], signal.SIGKILL)
        jobs.wait_for(2, seconds=30)
        assert sorted(jobs.events("gone")) == [0, 1]            # the runner hears its server is gone
        assert not server.alive
    finally:
        server.close()
    # the other forker killed its job as it ended
    wait_gone(started[1], "the job of the forker still alive outlived the server")
    assert not alive(jobs.parents[1])
    try:                                     # the dead forker's job ended with it (and ForkedRun kills it on "gone")
        wait_gone(started[0], "the job of the forker killed outlived it")
    finally:
        kill_orphan(started[0])


def test_a_server_killed_with_requests_unread_still_says_which_jobs_it_started(folder):
    # Linux answers the first read after such a death with a reset, although the server's earlier
    # replies are still queued: they must be read, or the started job's pid is lost and it runs on.
    server = ForkServer(limit=2, keep_spare=False).start()
    jobs = Jobs(server, folder)
    try:
        jobs.submit(0, str(folder / "hang.osc"))
        assert select.select([server.fileno()], [], [], 60)[0]   # "started" is queued, not read
        assert server.proc is not None
        os.kill(server.proc.pid, signal.SIGSTOP)
        deadline = time.monotonic() + 30
        while state_of(server.proc.pid) != "T":                    # stopped, not inside a read
            assert time.monotonic() < deadline
            time.sleep(0.01)
        jobs.submit(1, str(folder / "hang.osc"))                  # left unread by the stopped server
        os.kill(server.proc.pid, signal.SIGKILL)
        server.proc.wait(timeout=30)
        jobs.wait_for(2, seconds=30)
        assert [job for job, event, _pid in jobs.replies] == [0, 0, 1]
        assert jobs.events("started") == [0] and jobs.events("gone") == [0, 1]
        started = [pid for _job, event, pid in jobs.replies if event == "started"]
        wait_gone(started[0], "the job outlived its server")   # it ended with it (fork_child.die_with_parent)
    finally:
        server.close()
        for _job, event, pid in jobs.replies:
            if event == "started":
                kill_orphan(int(pid))


def test_a_server_killed_while_a_thread_waits_for_its_start_fails_that_start_and_kills_its_jobs(folder):
    # The reader thread's path (a blocking read): the reset, then the end, neither may leave a waiter hanging.
    server = ForkServer(limit=1, keep_spare=False).start()
    root = str(folder / "out")

    def spawn(job: int):
        return server.spawn(["scenario_execution", str(folder / "hang.osc"), "--output-dir", f"{root}/j{job}"],
                            cwd=str(folder), environment={}, log_path=f"{root}/j{job}/log.txt",
                            log_folder=(root, os.path.realpath(root)))

    failures: list[Exception] = []

    def second() -> None:
        try:
            spawn(1)
        except Exception as exc:  # noqa: BLE001 - recorded for the assertion
            failures.append(exc)

    first = None
    try:
        first = spawn(0)
        assert first is not None and server.proc is not None
        os.kill(server.proc.pid, signal.SIGSTOP)
        waiter = threading.Thread(target=second)
        waiter.start()
        time.sleep(0.5)                                           # its request sent, unread
        os.kill(server.proc.pid, signal.SIGKILL)
        waiter.join(timeout=30)
        assert not waiter.is_alive() and len(failures) == 1
        assert isinstance(failures[0], ForkServerError), failures   # (sent before the end, or refused after it)
        assert first.wait(timeout=30) == -signal.SIGKILL
        wait_gone(first.pid)                                      # killed as its server ended
    finally:
        server.close()
        if first is not None:
            kill_orphan(first.pid)


@pytest.mark.parametrize("keep_spare", [False, True], ids=["forked", "spare"])
def test_a_job_ends_with_the_process_that_forked_it_even_unseen_by_the_runner(folder, keep_spare):
    # The runner here never reads the server's end, so only the kernel can stop the job: a job forked
    # a moment before its forker died, whose "started" never left, is in that place.
    server = ForkServer(limit=1, keep_spare=keep_spare).start()
    jobs = Jobs(server, folder)
    pids: list[int] = []
    try:
        jobs.submit(0, str(folder / "hang.osc"))
        jobs.wait_for_starts(1)
        pids = [int(pid) for _job, event, pid in jobs.replies if event == "started"]
        assert server.proc is not None and parent_of(pids[0]) == server.proc.pid
        os.kill(server.proc.pid, signal.SIGKILL)
        server.proc.wait(timeout=30)
        wait_gone(pids[0], "the job outlived the process that forked it")
    finally:
        server.close()
        for pid in pids:
            kill_orphan(pid)


def test_the_parent_death_signal_leaves_no_module_to_the_jobs():
    # A job imports ctypes as a launched process would (its own ctypes.py first), so the server's
    # lookup of prctl must not leave ctypes loaded in what the jobs are forked from.
    code = ("import sys; import executor.batch.fork_child as c; "
            "print(c._PRCTL is not None, sorted(m for m in sys.modules if 'ctypes' in m or 'struct' in m))")
    shown = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert shown[0] == "True"
    assert "ctypes" not in " ".join(shown[1:])


#: The batch CLI in a process that believes it has 16 cores (so -j 8 forks from two forkers).
MANY_CORES = ("import sys; import executor.batch.builtin_runner as runner; runner.usable_cpus = lambda: 16; "
              "from cli.scenario_batch_execution import main; sys.argv[0] = 'scenario_batch_execution'; main()")


def test_a_batch_on_many_cores_forks_its_jobs_from_several_forkers(tmp_path):
    names = [f"m{i}" for i in range(24)]
    env = make_variants(tmp_path, names, pause=0.2)
    done = subprocess.run([sys.executable, "-c", MANY_CORES, "-i", "out", "-o", "res", "-j", "8"], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "24 passed" in done.stdout
    report = tmp_path / "res" / "test.xml"
    assert_valid(report)
    assert [s.get("name") for s in ET.parse(report).iter("testsuite")] == [f"job{i}" for i in range(24)]
    ledger = records(tmp_path)
    assert sorted(row[0] for row in ledger) == sorted(names)           # each job ran once
    parents = {row[2] for row in ledger}
    assert len(parents) == 2 and all(not alive(int(pid)) for pid in parents)   # two forkers, gone at the end


def test_kill_9_of_a_runner_with_several_forkers_leaves_no_process(tmp_path):
    names = [f"k{i}" for i in range(40)]
    env = make_variants(tmp_path, names, pause=0.3)
    runner = subprocess.Popen([sys.executable, "-c", MANY_CORES, "-i", "out", "-o", "res", "-j", "8"], cwd=tmp_path,
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 60
        while len(records(tmp_path)) < 8:
            assert time.monotonic() < deadline and runner.poll() is None, "the batch runs its jobs"
            time.sleep(0.02)
        with sqlite3.connect(tmp_path / ".scenario_store.db") as conn:
            (worker,) = conn.execute("SELECT worker_id FROM jobs WHERE worker_id IS NOT NULL LIMIT 1").fetchone()
        mark = f"SCENARIO_BATCH_RUNNER={worker}"
        forkers = [pid for server in children_of(runner.pid) for pid in children_of(server)]
        assert len([pid for pid in forkers if pid in marked(mark)]) >= 2      # the forkers (and their jobs)
        runner.send_signal(signal.SIGKILL)
        runner.communicate(timeout=10)
        wait_until_unmarked(mark, time.monotonic(), 5)
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.communicate(timeout=10)
