"""``run_process(command, wait_for_shutdown, shutdown_signal, shutdown_timeout)``.

The command is split like a shell would (``shlex``), but no shell is started. Each process runs in
its own session, so stopping it signals the whole group it started. Its output lines are logged and
kept for ``process_log_check``. With ``wait_for_shutdown: false`` the action succeeds as soon as the
process is started, and the process is stopped when the scenario ends: ``shutdown_signal`` first,
then SIGKILL after ``shutdown_timeout`` seconds.
"""

from __future__ import annotations

import os
import shlex
import signal
import subprocess
import threading
import time
from collections.abc import Callable
from typing import IO, Any

from py_trees.common import Status

from executor.actions.base import ActionBase, ActionError


def _signal_number(value: Any) -> int:
    if isinstance(value, tuple) and len(value) == 2:  # an enum member: (name, value)
        value = value[1]
    try:
        return int(value)
    except (TypeError, ValueError) as exc:
        raise ActionError(f"run_process(): bad shutdown_signal {value!r}") from exc


class RunProcess(ActionBase):
    """Starts a process on its first tick, then reports its state."""

    def __init__(self) -> None:
        super().__init__()
        self.command: list[str] = []
        self.wait_for_shutdown = True
        self.shutdown_signal = int(signal.SIGTERM)
        self.shutdown_timeout = 10.0
        self.process: subprocess.Popen | None = None
        self._started: list[subprocess.Popen] = []
        self._readers: list[threading.Thread] = []
        self._output: list[str] = []
        self._output_lock = threading.Lock()

    def setup(self, **kwargs: Any) -> None:
        context = kwargs.get("context")
        # process_log_check finds a process by the label the scenario gave it (as the reference does): an
        # unlabelled run_process is not found under its action name. The builder sets osc_labelled; a
        # behaviour made elsewhere (a test, a plugin) counts as labelled by its name.
        if context is not None and getattr(self, "osc_labelled", True):
            context.processes.setdefault(self.name, []).append(self)

    def execute(self, command: object = None, wait_for_shutdown: bool = True,
                shutdown_signal: object = ("sigterm", 15), shutdown_timeout: float = 10.0) -> None:
        if isinstance(command, str):
            try:
                self.command = shlex.split(command)
            except ValueError as exc:
                raise ActionError(f"run_process(): cannot split command {command!r}: {exc}") from exc
        elif isinstance(command, (list, tuple)):
            self.command = [str(part) for part in command]
        else:
            raise ActionError("run_process(): no command given")
        if not self.command:
            raise ActionError("run_process(): empty command")
        self.wait_for_shutdown = bool(wait_for_shutdown)
        self.shutdown_signal = _signal_number(shutdown_signal)
        self.shutdown_timeout = float(shutdown_timeout)
        self.process = None

    # -- ticking -----------------------------------------------------------------------------------

    def update(self) -> Status:
        if self.process is None:
            try:
                self.process = subprocess.Popen(self.command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                                stdin=subprocess.DEVNULL, start_new_session=True,
                                                preexec_fn=_default_signals)
            except OSError as exc:
                self.feedback_message = f"cannot start {shlex.join(self.command)}: {exc}"
                self.logger.error(self.feedback_message)
                return Status.FAILURE
            self._started.append(self.process)
            self.logger.debug(f"started '{shlex.join(self.command)}' (pid {self.process.pid})")
            self._read(self.process.stdout, self.logger.info)
            self._read(self.process.stderr, self.logger.error)
        code = self.process.poll()
        if code is None:
            self.feedback_message = f"running '{shlex.join(self.command)}'"
            return Status.RUNNING if self.wait_for_shutdown else Status.SUCCESS
        if code == 0:
            self.feedback_message = f"'{shlex.join(self.command)}' finished"
            return Status.SUCCESS
        self.feedback_message = f"'{shlex.join(self.command)}' failed with exit code {code}"
        return Status.FAILURE

    def _read(self, pipe: IO[bytes] | None, log: Callable[[str], None]) -> None:
        if pipe is None:      # never: both streams are pipes
            return

        def pump() -> None:
            for raw in iter(pipe.readline, b""):
                line = raw.decode(errors="replace").rstrip("\r\n")
                with self._output_lock:
                    self._output.append(line)
                log(line)
            pipe.close()

        reader = threading.Thread(target=pump, daemon=True)
        reader.start()
        self._readers.append(reader)

    def terminate(self, new_status: Status) -> None:
        """An abandoned branch (timeout, lost one_of) stops its process; finished ones keep running."""
        if new_status == Status.INVALID and self.process is not None and self.wait_for_shutdown:
            self._signal(self.process, self.shutdown_signal)

    # -- output for process_log_check --------------------------------------------------------------

    def output_lines(self) -> list[str]:
        with self._output_lock:
            return list(self._output)

    def output_complete(self) -> bool:
        """True once the process has exited and all its output has been read."""
        if self.process is None or self.process.poll() is None:
            return False
        return not any(reader.is_alive() for reader in self._readers)

    # -- end of scenario ---------------------------------------------------------------------------

    @staticmethod
    def _signal(process: subprocess.Popen, signum: int) -> None:
        try:
            os.killpg(process.pid, signum)
        except (ProcessLookupError, PermissionError):
            pass

    def shutdown(self) -> None:
        """Stop every process this action started that is still running (signal, wait, SIGKILL)."""
        running = [p for p in self._started if p.poll() is None]
        for process in running:
            self.logger.info(f"sending {signal.Signals(self.shutdown_signal).name} to pid {process.pid}")
            self._signal(process, self.shutdown_signal)
        deadline = time.monotonic() + self.shutdown_timeout
        for process in running:
            try:
                process.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                self.logger.info(f"pid {process.pid} ignored the signal, sending SIGKILL")
                self._signal(process, signal.SIGKILL)
                process.wait()
        # the group may hold children that outlived their parent
        for process in self._started:
            self._signal(process, signal.SIGKILL)
        for reader in self._readers:
            reader.join(0.5)


def _default_signals() -> None:
    """In the child: SIGINT and SIGTERM do what they do by default, even when we were started with them
    ignored (``nohup``, a background job of a script), so ``shutdown_signal`` stops the process."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
