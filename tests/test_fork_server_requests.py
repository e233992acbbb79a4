"""The fork server and its children, one request at a time: what goes wrong with one request stays with it.

Checked on the real fork server: a request it cannot prepare (for any reason) fails alone; requests
the socket refuses are answered as failed; a stop that reaches a job whose command has ended lets its
exit functions finish. The server serves on in every case.
"""

from __future__ import annotations

import os
import signal
import socket
import time
from pathlib import Path

import pytest
from fork_jobs import QUICK, Jobs, job_folder

from executor.batch.builtin_runner import ForkServer


@pytest.fixture
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    return job_folder(tmp_path, monkeypatch)


#: An external method that leaves an exit function behind: it says when it begins, waits for the test's
#: go (a file beside the marker), says when it ended.
ENDING_MODULE = """import atexit, pathlib, time

def _slow_end(marker):
    marker.write_text("ending")
    go = marker.with_name("go")
    deadline = time.monotonic() + 60
    while not go.exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    marker.write_text("ended")

def start(path):
    atexit.register(_slow_end, pathlib.Path(path))
    return "started"
"""

ENDING = """import osc.helpers

struct ending:
    def start(path: string) -> string is external ending_mod.start()

scenario ends_slowly:
    do serial:
        log(ending.start("{marker}"))
        emit end
"""


def test_a_stop_that_comes_while_a_job_ends_lets_its_exit_functions_finish_without_a_traceback(folder):
    """A cancel (SIGINT to the job's group) that reaches a job whose command has ended, while its exit
    functions run, waits for them: the job ends as it would have, its log holds no KeyboardInterrupt
    traceback (a -j 1 batch echoes that log to the terminal)."""
    marker = folder / "marker.txt"
    (folder / "ending_mod.py").write_text(ENDING_MODULE)
    (folder / "ending.osc").write_text(ENDING.format(marker=marker))
    server = ForkServer(limit=1).start()
    jobs = Jobs(server, folder)
    try:
        jobs.submit(0, str(folder / "ending.osc"))
        jobs.wait_for_starts(1)
        deadline = time.monotonic() + 60
        while not marker.exists():
            assert time.monotonic() < deadline, jobs.replies
            time.sleep(0.02)
        pid = jobs.messages[0]["pid"]
        os.killpg(pid, signal.SIGINT)                     # as the runner cancels a job
        time.sleep(0.2)                                    # (a handler that raised would have by now)
        (folder / "go").write_text("")
        jobs.wait_for(1)
    finally:
        server.close()
    status = next(m for m in jobs.messages if m.get("event") == "exited")["status"]
    log = (folder / "out" / "j0" / "log.txt").read_text()
    assert "Traceback" not in log and "KeyboardInterrupt" not in log, log
    assert marker.read_text() == "ended"
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0, status


@pytest.mark.parametrize("forkers", [1, 2])
def test_a_request_the_server_cannot_prepare_for_any_reason_fails_alone_and_the_server_serves_on(folder, forkers):
    """Whatever goes wrong while the server prepares a job (here a request whose output root is not a
    pair: a ValueError, not an OSError) ends that request as ``failed``; it does not end the server and,
    with it, the jobs it runs (each such request would otherwise cost a new server and every job on it)."""
    server = ForkServer(limit=2, forkers=forkers).start()
    jobs = Jobs(server, folder)
    try:
        jobs.submit(0, str(folder / "slow.osc"))
        jobs.wait_for_starts(1)
        out = folder / "out" / "bad"
        server.submit(["scenario_execution", str(folder / "quick.osc"), "--output-dir", str(out)], cwd=str(folder),
                      environment={}, log_path=str(out / "log.txt"), append=False, log_folder=(str(folder),),
                      reply=lambda message: jobs._heard(1, message))
        jobs.submit(2, str(folder / "quick.osc"))
        jobs.wait_for(3)
        assert server.alive
    finally:
        server.close()
    assert jobs.events("failed") == [1] and sorted(jobs.events("exited")) == [0, 2]
    failure = next(m for m in jobs.messages if m.get("event") == "failed")
    assert "internal error while preparing the job: ValueError" in str(failure["reason"])


def test_kept_requests_the_socket_refuses_are_answered_as_failed_while_the_server_lives_on(folder):
    """A message larger than the socket's send buffer is refused (EMSGSIZE) and the server never hears of
    those requests: each is answered here (``failed``), none waits for good, and the server serves on."""
    server = ForkServer(limit=1).start()
    jobs = Jobs(server, folder)
    try:
        server._sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)   # smaller than when it started
        long_name = folder / ("q" * 200 + ".osc")
        long_name.write_text(QUICK)
        for job in range(30):
            jobs.submit(job, str(long_name), later=True)
        server.send_submitted()
        assert sorted(jobs.events("failed")) == list(range(30)) and server.alive
        assert "could not be sent" in str(next(m for m in jobs.messages if m.get("event") == "failed")["reason"])
        jobs.submit(30, str(folder / "quick.osc"))                # one alone fits: it runs
        jobs.wait_for(31)
    finally:
        server.close()
    assert jobs.events("started") == [30] and jobs.events("exited") == [30]
