"""The watchdog of a runner: when the runner dies (even by ``kill -9``), every process it started dies too.

A runner starts one watchdog (a tiny process: this file run by the same interpreter with ``-I -S``, the
standard library only) and keeps the writing end of a pipe to it. Every process the runner starts —
launched commands, the built-in runner's fork server and its jobs, ``--post-run`` hooks — carries the
runner's mark in its environment (``SCENARIO_BATCH_RUNNER=<worker id>``), and so do their children,
which inherit it. The watchdog blocks on the pipe. When the runner ends normally it writes ``done``
first and the watchdog just leaves; when the pipe closes without it, the runner died, and the
watchdog kills (SIGKILL) the process group of every process that carries the mark, repeating until
none is left, then removes the private folders the runner named on the pipe (``remove <path>``
lines: the fork server's scratch folder), which no one else would remove. Detection is immediate
(the kernel closes the pipe), and a job costs nothing extra: no ``preexec_fn``, so launched
commands keep the fast ``vfork`` path.

Chosen over ``PR_SET_PDEATHSIG`` in each child (measured 4-6 ms per job for the full ``fork`` it
forces, and it reaches only the direct child, not its group) and over a pipe each child must watch
(which a foreign command would not do).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

#: How long the watchdog keeps looking for marked processes after the runner died.
PATIENCE = 3.0

#: What a runner that ends normally writes before it closes the pipe (a line of its own).
DONE = b"done"

#: The start of a line naming a folder to remove once the runner's processes are gone.
REMOVE = b"remove "


def marked_processes(mark: bytes, spare: set[int]) -> list[tuple[int, int]]:
    """``(pid, process group)`` of every process whose environment holds ``mark`` (``NAME=value``)."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) in spare:
            continue
        try:
            with open(f"/proc/{entry}/environ", "rb") as handle:
                if mark not in handle.read().split(b"\0"):
                    continue
            with open(f"/proc/{entry}/stat", "rb") as handle:
                pgid = int(handle.read().rsplit(b")", 1)[1].split()[2])
        except (OSError, ValueError, IndexError):
            continue
        found.append((int(entry), pgid))
    return found


def end_marked(mark: bytes, spare_groups: set[int], patience: float = PATIENCE) -> int:
    """Kill every marked process and its process group (never a group in ``spare_groups``); returns how many."""
    deadline = time.monotonic() + patience
    killed: set[int] = set()
    while True:
        found = marked_processes(mark, {os.getpid()})
        if not found:
            return len(killed)
        for pid, pgid in found:
            if pgid > 1 and pgid not in spare_groups:
                try:
                    os.killpg(pgid, signal.SIGKILL)
                except OSError:
                    pass
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
            killed.add(pid)
        if time.monotonic() > deadline:
            return len(killed)
        time.sleep(0.05)


def main(argv: list[str]) -> int:
    """``watchdog.py NAME=VALUE RUNNER_PGID``: wait for stdin to close, then end the marked processes."""
    mark, runner_group = argv[1].encode(), int(argv[2])
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGPIPE):
        signal.signal(sig, signal.SIG_IGN)
    received = b""
    while True:
        try:
            chunk = os.read(0, 64)
        except InterruptedError:
            continue
        except OSError:
            break
        if not chunk:
            break
        received += chunk
    lines = received.split(b"\n")
    if DONE not in lines:
        end_marked(mark, {runner_group, os.getpgrp()})
        import shutil

        for line in lines:
            if line.startswith(REMOVE):
                shutil.rmtree(line[len(REMOVE):], ignore_errors=True)
    return 0


class Watchdog:
    """The runner's side: start the watchdog; :meth:`release` when the runner ends normally."""

    def __init__(self, mark: str) -> None:
        self.mark = mark
        self.proc: subprocess.Popen | None = None

    def start(self) -> Watchdog:
        """Start the watchdog process (its own session: a Ctrl-C at the terminal is not for it)."""
        self.proc = subprocess.Popen(
            [sys.executable, "-I", "-S", os.path.abspath(__file__), self.mark, str(os.getpgrp())],
            stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, close_fds=True,
            start_new_session=True)
        return self

    def remove_on_death(self, path: str) -> None:
        """Should the runner die, remove the folder ``path`` (after its processes are gone)."""
        encoded = os.fsencode(path)
        if self.proc is None or self.proc.stdin is None or b"\n" in encoded:
            return
        try:
            self.proc.stdin.write(REMOVE + encoded + b"\n")
            self.proc.stdin.flush()
        except OSError:
            pass

    def release(self) -> None:
        """The runner ends normally: the watchdog leaves without killing anything."""
        if self.proc is None:
            return
        try:
            assert self.proc.stdin is not None
            self.proc.stdin.write(b"\n" + DONE + b"\n")
            self.proc.stdin.close()
        except OSError:
            pass
        try:
            self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        self.proc = None


if __name__ == "__main__":
    sys.exit(main(sys.argv))
