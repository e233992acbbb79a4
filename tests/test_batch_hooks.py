"""``--post-run`` hooks: the shared runner (real processes) and Ctrl-C while a batch job's hook runs."""

from __future__ import annotations

import signal
import sys
import threading
import time
from pathlib import Path

import pytest
from batch_fixtures import alive, child_command, cli_env, run_cli, start_cli, write_child, write_scenarios

from executor.children.hooks import run_post_hooks

#: A hook that records its pid in the folder it is given, then sleeps (ignoring SIGINT if asked). The pid
#: file appears whole (written aside, then renamed): a test that saw it empty once read it too early.
HOOK = r'''
import os, signal, sys, time
if len(sys.argv) > 2:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
aside = os.path.join(sys.argv[-1], "hook.pid.part")
open(aside, "w").write(str(os.getpid()))
os.replace(aside, os.path.join(sys.argv[-1], "hook.pid"))
time.sleep(float(sys.argv[1]))
'''

#: A hook that only leaves a mark: it must not run once the batch was interrupted.
MARK = "import os, sys\nopen(os.path.join(sys.argv[-1], 'second_hook_ran'), 'w').close()\n"


def _write_hooks(tmp_path: Path) -> tuple[Path, Path]:
    hook, mark = tmp_path / "hook.py", tmp_path / "mark.py"
    hook.write_text(HOOK)
    mark.write_text(MARK)
    return hook, mark


def _wait_for(path: Path, proc, timeout: float = 30) -> None:
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert proc is None or proc.poll() is None, proc.stdout.read()
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.02)


def _start_batch(tmp_path: Path, hook_args: str, grace: str):
    hook, mark = _write_hooks(tmp_path)
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"a": "", "b": ""})
    proc = start_cli(["-i", "in", "-o", "results", "--grace", grace,
                      "--post-run", f"{sys.executable} {hook} {hook_args}", "--post-run", f"{sys.executable} {mark}",
                      "--", *child_command(child)], tmp_path, cli_env(tmp_path))
    pid_file = tmp_path / "results" / "a" / "hook.pid"
    _wait_for(pid_file, proc)
    return proc, int(pid_file.read_text())


@pytest.mark.slow
def test_ctrl_c_ends_a_running_post_run_hook_and_skips_the_rest(tmp_path):
    # The hook would sleep 300 s; the runner must end it (well) before: the bound leaves a slow machine room.
    proc, hook_pid = _start_batch(tmp_path, "300", grace="5")
    began = time.monotonic()
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=120)
    assert time.monotonic() - began < 100, "the runner waited for the hook"
    assert proc.returncode == 130, out
    assert not alive(hook_pid)
    assert not (tmp_path / "results" / "a" / "second_hook_ran").exists()
    assert not (tmp_path / "results" / "b").exists()              # no new job after Ctrl-C
    assert "$ " in (tmp_path / "results" / "a" / "post_run.log").read_text()


def test_second_ctrl_c_kills_a_hook_that_ignores_sigint(tmp_path):
    proc, hook_pid = _start_batch(tmp_path, "300 ignore-sigint", grace="200")
    proc.send_signal(signal.SIGINT)
    time.sleep(1.0)
    assert proc.poll() is None and alive(hook_pid), "the hook ignores SIGINT: the grace period runs"
    began = time.monotonic()
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=240)
    assert time.monotonic() - began < 100, "the second Ctrl-C did not end the hook (the grace period is 200 s)"
    assert proc.returncode == 130, out
    assert not alive(hook_pid)


def test_hooks_in_order_failures_reported_cancel_skips_the_rest(tmp_path):
    hook, mark = _write_hooks(tmp_path)
    log = tmp_path / "post_run.log"
    problems = run_post_hooks([f"{sys.executable} -c 'import sys; sys.exit(4)'", "'unbalanced",
                               "no-such-program-xyz", f"{sys.executable} {mark}"], tmp_path, log_path=log)
    assert len(problems) == 3, problems
    assert problems[0].endswith("failed with exit code 4")
    assert problems[1] == "post-run ''unbalanced': No closing quotation"
    assert problems[2].startswith("post-run 'no-such-program-xyz' could not start")
    assert (tmp_path / "second_hook_ran").exists()
    assert log.read_text().count("$ ") == 3                      # the one that could not be split has no line

    (tmp_path / "second_hook_ran").unlink()
    stop = threading.Event()
    running: list = []

    def track(child):
        running.append(child)
        if child is not None and stop.is_set():
            child.cancel(0)

    def cancel_when_started():
        _wait_for(tmp_path / "hook.pid", None)
        stop.set()
        running[-1].cancel(0.5)

    threading.Thread(target=cancel_when_started, daemon=True).start()
    began = time.monotonic()
    problems = run_post_hooks([f"{sys.executable} {hook} 30 ignore-sigint", f"{sys.executable} {mark}"], tmp_path,
                              log_path=log, cancelled=stop.is_set, track=track)
    assert time.monotonic() - began < 10
    assert len(problems) == 1 and problems[0].endswith("cancelled")
    assert not (tmp_path / "second_hook_ran").exists()
    assert running[-1] is None                                   # the tracker is told when a hook ended


def test_empty_post_run_is_a_usage_error(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"a": ""})
    for hook in ("", "   ", "'open"):
        result = run_cli(["-i", "in", "-o", "results", "--post-run", hook, "--", *child_command(child)], tmp_path)
        assert result.returncode == 2, (hook, result.stdout + result.stderr)
        assert "--post-run" in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "ledger.txt").exists()
