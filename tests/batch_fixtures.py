"""Shared helpers of the batch and queue tests: a scriptable child and the real CLI.

The child (:data:`CHILD`) reads directives from the scenario file it is given (``key=value`` lines):
``sleep``, ``exit``, ``xml`` (pass, fail, error, garbage, none, empty, two), ``print``, ``output_mb``,
``hang`` (ignore SIGTERM and sleep), ``grandchild`` (start a sleeping grandchild in its group),
``fail_first`` (no result on the first attempt), ``slow_first`` (sleep this long on the first attempt),
so each test states its jobs as data.
Every child that gets to its end appends ``<name> <pid>`` to the ledger named by ``$BATCH_LEDGER``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

BIN = Path(sys.executable).parent
CLI = str(BIN / "scenario_batch_execution")

CHILD = r'''
import os, signal, subprocess, sys, time
scenario, out = sys.argv[1], sys.argv[2]
name = os.path.splitext(os.path.basename(scenario))[0]
spec = {}
for line in open(scenario):
    if "=" in line:
        key, value = line.strip().split("=", 1)
        spec[key] = value
os.makedirs(out, exist_ok=True)
print("start", name, flush=True)
if "print" in spec:
    print(spec["print"], flush=True)
if spec.get("fail_first") and not os.path.exists(os.path.join(out, "first_attempt_done")):
    open(os.path.join(out, "first_attempt_done"), "w").close()
    print("first attempt: no result", flush=True)
    sys.exit(3)
if "grandchild" in spec:
    code = "import os, signal, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); time.sleep(1000)"
    grand = subprocess.Popen([sys.executable, "-S", "-c", code])
    open(os.path.join(out, "grandchild.pid"), "w").write(str(grand.pid))
if spec.get("slow_first") and not os.path.exists(os.path.join(out, "slow_first_done")):
    open(os.path.join(out, "slow_first_done"), "w").close()
    open(os.path.join(out, "child.pid"), "w").write(str(os.getpid()))
    time.sleep(float(spec["slow_first"]))
if "output_mb" in spec:
    block = b"x" * 1023 + b"\n"
    for _ in range(int(spec["output_mb"]) * 1024):
        sys.stdout.buffer.write(block)
    sys.stdout.flush()
if "hang" in spec:
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    time.sleep(1000)
if "sleep" in spec:
    time.sleep(float(spec["sleep"]))
xml = spec.get("xml", "pass")
docs = {
    "pass": '<testsuite tests="1"><testcase classname="c" name="sc" time="0.01"/></testsuite>',
    "fail": '<testsuite tests="1"><testcase classname="c" name="sc"><failure message="it failed">why</failure></testcase></testsuite>',
    "error": '<testsuite tests="1"><testcase classname="c" name="sc"><error message="it erred"/></testcase></testsuite>',
    "two": '<testsuites><testsuite tests="2"><testcase classname="c" name="first"/><testcase classname="c" name="second"><failure message="f"/></testcase></testsuite></testsuites>',
    "garbage": '<testsuite><testcase name="broken"',
    "empty": '<testsuite tests="0"></testsuite>',
}
if xml in docs:
    with open(os.path.join(out, "test.xml"), "w") as handle:
        handle.write(docs[xml])
ledger = os.environ.get("BATCH_LEDGER")
if ledger:
    fd = os.open(ledger, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    os.write(fd, ("%s %d\n" % (name, os.getpid())).encode())
    os.close(fd)
sys.exit(int(spec.get("exit", "0")))
'''


def write_child(folder: Path) -> Path:
    """Write the scriptable child into ``folder``; returns its path."""
    path = folder / "child.py"
    path.write_text(CHILD)
    return path


def child_command(child: Path) -> list[str]:
    """The launch command running the child (``python -S`` starts in a few milliseconds)."""
    return [sys.executable, "-S", str(child), "{SCENARIO}", "{OUTPUT_DIR}"]


def write_scenarios(folder: Path, specs: dict[str, str], suffix: str = ".sce") -> Path:
    """Create ``folder`` with one scenario file per name, its text the child's directives."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in specs.items():
        (folder / f"{name}{suffix}").write_text(text + "\n")
    return folder


def cli_env(tmp_path: Path, **extra: str) -> dict[str, str]:
    """Environment for the CLI: plain output, a store in ``tmp_path``, a ledger file."""
    env = dict(os.environ)
    env.pop("SCENARIO_STORE", None)
    env.update({"NO_COLOR": "1", "BATCH_LEDGER": str(tmp_path / "ledger.txt"), "PYTHONUNBUFFERED": "1"})
    env.update(extra)
    return env


def run_cli(args: list[str], cwd: Path, env: dict[str, str] | None = None,
            timeout: float = 120) -> subprocess.CompletedProcess:
    """Run the real console script and capture its output."""
    return subprocess.run([CLI, *args], cwd=cwd, env=env or cli_env(cwd), capture_output=True, text=True,
                          timeout=timeout)


#: Runners started in the background by the running test; ``end_started`` ends what a failed test left.
STARTED: list[subprocess.Popen] = []


def start_cli(args: list[str], cwd: Path, env: dict[str, str]) -> subprocess.Popen:
    """Start the real console script in the background (for kill and interrupt tests)."""
    process = subprocess.Popen([CLI, *args], cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True)
    STARTED.append(process)
    return process


def end_started() -> None:
    """Kill and reap every runner a test started and left running (a failed assertion leaves one behind,
    and its unclosed pipe would otherwise be reported as a warning in whichever test runs next)."""
    while STARTED:
        process = STARTED.pop()
        if process.poll() is None:
            process.kill()
        try:
            process.communicate(timeout=10)
        except subprocess.TimeoutExpired:          # a child that outlived it still holds the pipe
            if process.stdout is not None:
                process.stdout.close()


def ledger(tmp_path: Path) -> Counter:
    """How often each job's child reached its end."""
    path = tmp_path / "ledger.txt"
    if not path.exists():
        return Counter()
    return Counter(line.split()[0] for line in path.read_text().splitlines() if line.strip())


def sqlite_url(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'store.db'}"


def alive(pid: int) -> bool:
    """Whether process ``pid`` still runs (a zombie waiting for its parent counts as gone)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:
        with open(f"/proc/{pid}/stat", "rb") as handle:
            return handle.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except OSError:
        return False


def children_of(pid: int) -> list[tuple[int, bytes]]:
    """``(pid, command line)`` of the processes whose parent is ``pid``."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as handle:
                parent = int(handle.read().rsplit(b")", 1)[1].split()[1])
            if parent == pid:
                with open(f"/proc/{entry}/cmdline", "rb") as handle:
                    found.append((int(entry), handle.read()))
        except (OSError, ValueError, IndexError):
            continue
    return found


def server_of(runner: int) -> int | None:
    """The fork server among ``runner``'s children (None while there is none)."""
    return next((pid for pid, cmdline in children_of(runner) if b"executor.batch.fork_server" in cmdline), None)


def watchdog_of(runner: int) -> int:
    """The process id of the watchdog the runner ``runner`` started."""
    found = [pid for pid, cmdline in children_of(runner) if b"watchdog.py" in cmdline]
    assert len(found) == 1, children_of(runner)
    return found[0]


def wait_until_unmarked(mark: str, since: float, seconds: float) -> None:
    """Wait until no process carries ``mark`` (see :func:`marked`); fail if one does ``seconds`` after ``since``."""
    while marked(mark):
        assert time.monotonic() - since < seconds, f"alive {seconds} s after kill -9: {marked(mark)}"
        time.sleep(0.05)


def marked(mark: str) -> list[int]:
    """Processes whose environment holds ``mark`` (``NAME=value``): what a runner started, still alive."""
    wanted = mark.encode()
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/environ", "rb") as handle:
                if wanted in handle.read().split(b"\0") and alive(int(entry)):
                    found.append(int(entry))
        except OSError:
            continue
    return found
