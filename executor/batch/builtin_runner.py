"""The built-in runner: jobs run ``scenario_execution`` forked from a warm fork server, not launched.

A batch without a launch command runs each job as ``scenario_execution {SCENARIO} --output-dir
{OUTPUT_DIR}`` would run, but the process comes from :mod:`executor.batch.fork_server` (one per worker,
started on the first such job), which has the command and the runtime imported and the standard
libraries parsed. :class:`ForkServer` is the worker's side; its :meth:`~ForkServer.spawn` returns a
:class:`ForkedProcess` that :class:`executor.children.process.ChildProcess` uses like a ``subprocess.Popen``,
so timeouts, cancellation, logs, echo, hooks and verdicts are the same code for both kinds of job.

Measured, and why a fresh fork per job rather than a worker recycled after each job: a recycled worker
saves the fork (about 1 ms from a 25 MB server), but must itself be replaced after every job to keep
jobs apart, which is the same fork at another moment; forking on demand is the simpler of the two.
What a fork does cost is the pages a run writes (about 1,500 copied, 5 ms): with a core to spare the
server forks the next job's process ahead and lets it copy them on our own probe meanwhile
(``keep_spare``, see :mod:`executor.batch.fork_server`).

:func:`spare_cores` decides: a spare pays off only while fewer jobs run than there are cores.
"""

from __future__ import annotations

import itertools
import json
import os
import select
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable, Mapping, Sequence
from typing import BinaryIO

from executor.batch.fork_errors import PEER_GONE, ForkServerEnded, ForkServerError, start_failure
from executor.batch.fork_protocol import MAX_MESSAGE, bundles, command_target, receive, send
from executor.batch.forked_process import ForkedProcess, Pending
from executor.children.process import RUNNER_ENV, StartTicket, kill_orphan

#: The command a built-in job runs (what ``-- scenario_execution {SCENARIO} --output-dir {OUTPUT_DIR}`` says).
BUILTIN_COMMAND = ("scenario_execution", "{SCENARIO}", "--output-dir", "{OUTPUT_DIR}")

#: Seconds the fork server may take to import and preload before the job fails.
START_TIMEOUT = 120.0


def usable_cpus() -> int:
    """The CPUs this process may run on (a CPU set given by ``taskset`` or a container's ``--cpuset-cpus``), at least 1.

    What ``-j auto`` runs in parallel, and what a spare child is weighed against: ``os.cpu_count()``
    counts the whole machine, and 64 jobs on the 2 CPUs a container was given only queue up. A CPU
    *quota* (``docker --cpus``, a Kubernetes CPU limit) is not seen here: give ``-j N`` there.
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def spare_cores(slots: int) -> bool:
    """Whether this machine has a core left over when ``slots`` jobs run (for a warm spare child)."""
    return slots < usable_cpus()


#: Job slots one forking process is given (see :mod:`executor.batch.fork_dispatch`): measured on 2 cores,
#: the fork server's own CPU per trivial job is about a fifth of the job's, so one forker keeps about
#: five slots busy; four leaves it room.
SLOTS_PER_FORKER = 4


def forkers_for(slots: int) -> int:
    """How many processes fork the jobs of ``slots`` at once: one per :data:`SLOTS_PER_FORKER` slots, and
    no more than one per that many usable cores (each forker is one more warm interpreter, and on few
    cores the jobs themselves are the bottleneck, not their forks)."""
    return max(1, min(-(-slots // SLOTS_PER_FORKER), usable_cpus() // SLOTS_PER_FORKER))


class ForkServer:
    """The worker's handle on its fork server: start it, spawn jobs, stop it.

    The server's probe runs write to a private folder this side makes and removes (``scratch``);
    ``on_scratch`` is told its path as soon as it exists (the worker's watchdog removes it should this
    process be killed). ``limit``: jobs the server runs at once (0: no limit); a :meth:`spawn` beyond
    that waits until the server starts it, the moment a running job ends.
    """

    def __init__(self, environment: Mapping[str, str] | None = None, *, keep_spare: bool = False,
                 on_scratch: Callable[[str], None] | None = None, limit: int = 0, forkers: int = 1) -> None:
        self.environment = dict(os.environ if environment is None else environment)
        self.keep_spare = keep_spare
        self.limit = limit
        self.forkers = forkers                     # processes that fork the jobs (see fork_dispatch)
        self.on_scratch = on_scratch
        self.scratch: str | None = None
        self.proc: subprocess.Popen | None = None
        self._sock: socket.socket | None = None
        self._lock = threading.Lock()              # one request on the socket at a time
        self._table_lock = threading.Lock()
        self._pending: dict[str, Pending] = {}
        self._running: dict[str, ForkedProcess] = {}
        self._early: dict[str, int] = {}           # exits that came before the spawner took its process
        self._replies: dict[str, Callable[[dict], None]] = {}   # submitted requests: who hears of them
        self._outbox: dict[str, bytes] = {}        # requests submitted to be sent later (see send_submitted)
        self._bundle_limit = MAX_MESSAGE           # the largest message the socket takes (see wait_ready)
        self._receiving = threading.Lock()         # one reader of the replies at a time, each dispatched in order
        self._reader: threading.Thread | None = None   # reads the replies once a thread waits in spawn()
        self._ids = itertools.count(1)
        self._alive = False
        self._starting: socket.socket | None = None   # launched, not yet ready (see launch)

    @property
    def alive(self) -> bool:
        return self._alive

    @property
    def setup(self) -> tuple[int, bool, int, str | None]:
        """How it was (or is to be) started: limit, spare, forkers and the runner's mark."""
        return self.limit, self.keep_spare, self.forkers, self.mark

    @property
    def mark(self) -> str | None:
        """``RUNNER_ENV=<worker id>`` when the server's environment has it: every process it forks carries it."""
        runner = self.environment.get(RUNNER_ENV)
        return None if runner is None else f"{RUNNER_ENV}={runner}"

    def start(self) -> ForkServer:
        """Start the server and wait until it is ready; :class:`ForkServerError` if it cannot be."""
        return self.launch().wait_ready()

    def launch(self) -> ForkServer:
        """Start the server's process, not waiting for it: its imports and preload go on meanwhile, and
        :meth:`wait_ready` waits for them; :class:`ForkServerError` if it cannot be started."""
        mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        script_dir = os.path.dirname(sys.executable)
        code = ("import sys; sys.path[0] = sys.argv[1]; from executor.batch.fork_server import serve; "
                "serve(int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5] == 'spare', int(sys.argv[6]), "
                "int(sys.argv[7]))")
        try:
            target = command_target()
            self.scratch = tempfile.mkdtemp(prefix="scenario_fork_server_")
        except (RuntimeError, OSError) as exc:
            mine.close()
            theirs.close()
            raise ForkServerError(f"the built-in runner cannot start: {exc}") from None
        if self.on_scratch is not None:
            self.on_scratch(self.scratch)
        try:
            self.proc = subprocess.Popen([sys.executable, "-c", code, script_dir, str(theirs.fileno()), target,
                                          self.scratch, "spare" if self.keep_spare else "no-spare",
                                          str(self.limit), str(self.forkers)],
                                         pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL,
                                         stdout=subprocess.DEVNULL, env=self.environment,
                                         start_new_session=True, close_fds=True)
        except OSError as exc:
            mine.close()
            raise ForkServerError(f"cannot start the built-in runner: {exc.strerror or exc}") from exc
        finally:
            theirs.close()
        self._starting = mine
        return self

    def wait_ready(self) -> ForkServer:
        """Wait until the launched server is ready (see :meth:`launch`); :class:`ForkServerError` if it
        ended instead, or said why it cannot serve."""
        mine, self._starting = self._starting, None
        if mine is None:
            raise ForkServerError("the built-in runner cannot start: it was closed before it was ready")
        mine.settimeout(START_TIMEOUT)
        try:
            message, _ = receive(mine)
        except OSError as exc:
            message = {"event": "unavailable", "reason": str(exc)}
        if not message or message.get("event") != "ready":
            reason = (message or {}).get("reason", "it ended at once")
            mine.close()
            self._end_process()
            raise ForkServerError(f"the built-in runner cannot start: {reason}")
        mine.settimeout(None)
        # a Unix datagram socket refuses a message larger than its send buffer (the kernel reports it doubled)
        self._bundle_limit = min(MAX_MESSAGE, mine.getsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF) // 2)
        self._sock = mine
        self._alive = True
        return self

    def spawn(self, argv: Sequence[str], *, cwd: str | None, environment: Mapping[str, str],
              output_fd: int | None = None, stdout: BinaryIO | None = None,
              ticket: StartTicket | None = None, log_path: str | None = None,
              append: bool = False, log_folder: tuple[str, str] | None = None) -> ForkedProcess | None:
        """Fork a job running ``argv`` (``scenario_execution …``) with its output going to ``output_fd``, or
        to ``log_path``, which the server opens as the job starts (this process makes no file per job),
        after making its folder when ``log_folder`` says under which root (the root, its real path);
        waits while the server runs ``limit`` jobs. None when ``ticket`` was withdrawn before the start.
        :class:`ForkServerEnded` when the server ended before the start, another :class:`ForkServerError`
        when it could not start the job."""
        self._ensure_reader()
        request_id = str(next(self._ids))
        pending = Pending()
        with self._table_lock:
            self._pending[request_id] = pending
        with self._lock:
            if not self._alive or self._sock is None:
                self._forget(request_id)
                raise ForkServerEnded("the built-in runner's fork server has ended")
            if ticket is not None and not ticket.on_withdraw(lambda: self._withdraw(request_id)):
                self._forget(request_id)
                return None
            request: dict[str, object] = {"id": request_id, "argv": list(argv), "cwd": cwd, "env": dict(environment)}
            if output_fd is None:
                request.update(log=log_path, append=append, folder=log_folder)
            try:
                self._send_kept()                          # those submitted before it go first
                self._send(request, None if output_fd is None else [output_fd])
            except OSError as exc:                         # (a ForkServerError too: ForkServerEnded when it had ended)
                self._forget(request_id)
                if isinstance(exc, ForkServerError):
                    raise
                if exc.errno in PEER_GONE or not self._alive:
                    raise ForkServerEnded(f"the built-in runner's fork server is gone: {exc}") from exc
                raise ForkServerError(f"the built-in runner cannot send the job to its fork server: {exc}") from exc
        if ticket is not None:
            ticket.sent()
        pending.event.wait()
        if pending.withdrawn:
            return None
        if pending.pid is None:
            if pending.gone:
                raise ForkServerEnded(f"the built-in runner could not start the job: {pending.reason}")
            raise start_failure(pending.reason, pending.errno, pending.folder_refused)
        process = ForkedProcess(pending.pid, stdout)
        with self._table_lock:
            early = self._early.pop(request_id, None)
            gone = early is None and not self._alive    # the server ended right after it said "started"
            if early is None and not gone:
                self._running[request_id] = process
        if gone:                                        # (its end killed only the jobs it knew of)
            kill_orphan(process.pid, self.mark)
            early = -signal.SIGKILL
        if early is not None:
            process._exited(early)
        return process

    def submit(self, argv: Sequence[str], *, cwd: str | None, environment: Mapping[str, str], log_path: str,
               append: bool, log_folder: tuple[str, str] | None, reply: Callable[[dict], None],
               later: bool = False) -> str:
        """Send a spawn request without waiting for its start (the worker's own loop, no thread per job);
        returns the request's id (for :meth:`withdraw`). ``later``: keep it for :meth:`send_submitted`,
        which sends those kept in one message (the requests reach the server in the order submitted).

        ``reply`` is called by whoever reads the replies (the worker's loop through :meth:`poll`, or the
        reader thread once a thread waits in :meth:`spawn`) with each of the server's messages on the
        request, in order: ``started`` (``pid``), ``failed`` (``reason``, ``errno``, ``folder``) or ``withdrawn``, then
        ``exited`` (the raw wait ``status``); ``{"event": "gone"}`` when the server ended before it could
        say more (a job it had started was killed with it). :class:`ForkServerEnded` when the request
        cannot be sent (the server ended before)."""
        request_id = str(next(self._ids))
        with self._table_lock:
            self._replies[request_id] = reply
        request = {"id": request_id, "argv": list(argv), "cwd": cwd, "env": dict(environment), "log": log_path,
                   "append": append, "folder": log_folder}
        with self._lock:
            if not self._alive or self._sock is None:
                with self._table_lock:
                    self._replies.pop(request_id, None)
                raise ForkServerEnded("the built-in runner's fork server has ended")
            self._outbox[request_id] = json.dumps(request).encode()
            if not later:
                self._send_kept()
        return request_id

    def send_submitted(self) -> None:
        """Send the requests :meth:`submit` kept (``later``): one wake-up of the server for all of them."""
        with self._lock:
            self._send_kept()

    def _send_kept(self) -> None:
        """Send the kept requests (holding ``_lock``). Should the server have ended, its end answered them
        (``gone``, see :meth:`_ended`); those the socket refuses are answered here: ``gone`` when the
        server has just died (its end not read yet), else ``failed``; the server never heard of them."""
        if not self._outbox or not self._alive or self._sock is None:
            return
        kept = list(self._outbox.items())
        self._outbox.clear()
        sent = 0
        try:
            for count, message in bundles([request for _id, request in kept], self._bundle_limit):
                self._send(message)
                sent += count
        except OSError as exc:                       # (a ForkServerError: it ended meanwhile)
            if self._alive:                          # (else its end answered them: "gone")
                unsent = [request_id for request_id, _request in kept[sent:]]
                if exc.errno in PEER_GONE:          # it died, its end not read yet: as its end would
                    self._answer_unsent(unsent, {"event": "gone"})
                else:
                    self._answer_unsent(unsent, {"event": "failed",
                                                 "reason": f"its request could not be sent: {exc.strerror or exc}"})

    def _answer_unsent(self, request_ids: list[str], answer: dict) -> None:
        """Answer requests the server never got (``failed``, ``withdrawn``, ``gone``) as it, or its end, would have."""
        with self._table_lock:
            replies = [(request_id, self._replies.pop(request_id, None)) for request_id in request_ids]
        for request_id, reply in replies:
            if reply is not None:
                reply({"id": request_id, **answer})

    def withdraw(self, request_id: str) -> None:
        """Take back a submitted request that still waits for a slot (answered ``withdrawn``, or
        ``started`` when it had begun: stop that one as any other)."""
        with self._lock:
            kept = self._outbox.pop(request_id, None) is not None
        if kept:
            self._answer_unsent([request_id], {"event": "withdrawn"})
        else:
            self._withdraw(request_id)

    def _forget(self, request_id: str) -> None:
        with self._table_lock:
            self._pending.pop(request_id, None)

    def _withdraw(self, request_id: str) -> None:
        """Ask the server to drop a request that still waits for a slot (it answers ``withdrawn``)."""
        with self._lock:
            if self._sock is None:
                return
            try:
                self._send({"withdraw": request_id})
            except OSError:
                pass                 # the server is gone: the reader fails every pending request

    def _send(self, message: dict | bytes, fds: list[int] | None = None) -> None:
        """Send one message (holding ``_lock``) without ever blocking on a full socket while nobody reads the
        replies: the server, blocked on its own full socket, would never read ours (with thousands of
        jobs in flight). When there is no room, the replies that came are read first."""
        assert self._sock is not None
        while True:
            try:
                send(self._sock, message, fds, socket.MSG_DONTWAIT)
                return
            except BlockingIOError:
                if self._reader is None and not self._drain():
                    raise ForkServerEnded("the built-in runner's fork server has ended") from None
                select.select([], [self._sock], [], 0.05)

    def _ensure_reader(self) -> None:
        """A thread waits in :meth:`spawn`: from now on a thread of our own reads the replies (the worker's
        loop may be busy with the store meanwhile, and the waiting job's timer must not outrun its end)."""
        with self._table_lock:
            if self._reader is None:
                self._reader = threading.Thread(target=self._read, name="fork-server-replies", daemon=True)
                self._reader.start()

    def _read(self) -> None:
        """The reader thread: dispatch replies until the server ends."""
        while True:
            with self._receiving:
                sock = self._sock
                if sock is None or not self._take_reply(sock, 0):
                    return

    def _take_reply(self, sock: socket.socket, flags: int) -> bool:
        """Receive and dispatch one reply (holding ``_receiving``); False when the server has ended (its
        jobs killed, its waiters failed). With ``socket.MSG_DONTWAIT``, :class:`BlockingIOError` when none came."""
        try:
            message, _ = receive(sock, flags=flags, after_reset=True)
        except BlockingIOError:
            raise
        except OSError:
            message = None
        if message is None:
            self._ended()
            return False
        self._dispatch(message)
        return True

    def fileno(self) -> int:
        """The socket the worker's loop watches for replies (readable: call :meth:`poll`); -1 when closed,
        or while a thread of our own reads them."""
        return -1 if self._sock is None or self._reader is not None else self._sock.fileno()

    def poll(self) -> bool:
        """Dispatch every reply the server has sent so far (without waiting); False once it has ended.

        The worker's loop calls this whenever :meth:`fileno` is readable: a job's start and end reach
        their waiters (a submitted request's ``reply``) through the loop, with no thread of the
        server's own, until a thread waits in :meth:`spawn` (then its reader does it). When the
        server ends, its jobs are killed and what waits for it fails.
        """
        if self._reader is not None:
            return self._alive
        return self._drain()

    def _drain(self) -> bool:
        with self._receiving:
            while (sock := self._sock) is not None:
                try:
                    if not self._take_reply(sock, socket.MSG_DONTWAIT):
                        return False
                except BlockingIOError:
                    return True
        return False

    def _ended(self) -> None:
        """The server is gone: kill its jobs, fail the requests that wait for it (once)."""
        self._alive = False
        with self._table_lock:
            pending = list(self._pending.values())
            running = list(self._running.values())
            replies = list(self._replies.values())
            self._pending.clear()
            self._running.clear()
            self._replies.clear()
        for reply in replies:
            reply({"event": "gone"})
        for item in pending:
            item.reason = "the fork server ended"
            item.gone = True
            item.event.set()
        for process in running:            # their parent is gone: nobody else can wait for them
            kill_orphan(process.pid, self.mark)
            process._exited(-signal.SIGKILL)

    def _dispatch(self, message: dict) -> None:
        request_id, event = str(message.get("id")), message.get("event")
        with self._table_lock:
            reply = self._replies.get(request_id)
            if reply is not None and event in ("failed", "withdrawn", "exited"):
                del self._replies[request_id]          # the last word on it
        if reply is not None:
            reply(message)
        elif event in ("started", "failed", "withdrawn"):
            with self._table_lock:
                pending = self._pending.pop(request_id, None)
            if pending is not None:
                pending.pid = message.get("pid") if event == "started" else None
                pending.reason = message.get("reason")
                pending.errno = message.get("errno")
                pending.folder_refused = bool(message.get("folder"))
                pending.withdrawn = event == "withdrawn"
                pending.event.set()
        elif event == "exited":
            code = os.waitstatus_to_exitcode(message["status"])
            with self._table_lock:
                process = self._running.pop(request_id, None)
                if process is None:
                    self._early[request_id] = code
            if process is not None:
                process._exited(code)

    def close(self) -> None:
        """Stop the server (it kills the jobs still running) and wait for it. One launched and never waited
        for ends as soon as it finds the socket closed: when its preload is done, or at once if it was
        serving already (its spare, a process of its own, ends with it: a SIGKILL of the server alone
        would leave the spare warming up in the scratch folder)."""
        self._alive = False
        if self._starting is not None:
            self._starting.close()
            self._starting = None
        if self._sock is not None:
            try:
                self._sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
            self._sock.close()
            self._sock = None
            self._ended()                  # nothing waits for a reply that will not come
        self._end_process()

    def _end_process(self) -> None:
        if self.proc is not None:
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
            self.proc = None
        if self.scratch is not None:     # what the probe runs left, a spare's killed while it warmed up
            shutil.rmtree(self.scratch, ignore_errors=True)
            self.scratch = None
