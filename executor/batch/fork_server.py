"""The fork server of the built-in runner: a warm process that forks one child per job.

Started once per worker (``python -c …serve()``), it imports the ``scenario_execution`` command and
the runtime, parses the standard ``.osc`` libraries, and then only forks: each request becomes a
child that turns itself into what ``scenario_execution SCENARIO --output-dir OUTPUT_DIR`` would have
been as a fresh process — its own session and process group, stdin from ``/dev/null``, stdout and
stderr into the file descriptor the runner sent, the runner's working directory and environment
plus the job's marker, default signal handling, fresh ``sys.std*`` objects buffered as a new
interpreter's would be — and runs the command's ``main()``. So a job costs a fork and the scenario,
not an interpreter start, and its files, output and exit status are those of the launched command.

When the runner has a core to spare (fewer job slots than cores), the server also keeps one *spare*
child: forked ahead of time, it runs the same probe the server ran at start (our own scenario, never
a user's) and then waits for a job. The probe makes the spare copy the memory pages a run writes
(Python writes reference counts into every object it touches, so a fresh fork copies over a
thousand pages: 4-5 ms), while the previous job still runs on the other core; the job handed to it
then starts on warm pages. Measured: a job's run 3.8 ms instead of 9.4 ms. With every core busy a spare
only adds the probe's work, so the server keeps none.

What the child does to become the job is :mod:`executor.batch.fork_child`. With many job slots the
server forks the jobs from several warm copies of itself (:mod:`executor.batch.fork_dispatch`).

Nothing of a scenario ever runs in the server: plugins, external methods and the scenario folder's
modules are imported by the child that needs them, and die with it, so a job that crashes, leaks,
changes global state or hangs cannot touch the next one.

Protocol (a Unix socket pair, one message per ``sendmsg``): the runner sends ``spawn`` requests as
JSON (several in one message as ``requests`` where none carries a descriptor) with the job's output
file descriptor attached, or naming the job's log (``log``, ``append``)
and its output root (``folder``), so the server makes the job's folder and opens its log when the
job starts (the runner's process then does no file-system work per job); the server answers ``started`` (the child's pid)
or ``failed`` (why not), and ``exited`` with the raw wait status when the child ends, both stamped with
the moment (``at``, ``time.monotonic``, one clock for every process of the host: the runner may read
them later, see :mod:`executor.batch.hand_over`). The server
reaps its children and ends when the runner closes its end (it died or is done): it then kills
the process groups of the children still running, so no job outlives its runner.

The server runs at most ``limit`` jobs at once (the runner's ``-j``): a request that comes while
that many run waits in the server, in order, and is forked the moment a job ends, by the process
that reaps it. So the runner can hand over each slot's next job while the slot is still busy, and a
slot is not left idle while the runner records the last result, claims, and prepares the next
(measured: 1.36 of 2 slots busy on average when the runner refilled them itself). A ``withdraw``
message takes back a request that still waits (answered ``withdrawn``; one that has started is
not stopped by it: the runner cancels that child as any other).
"""

from __future__ import annotations

import os
import select
import signal
import socket
import sys
import time
from typing import TYPE_CHECKING

from executor.batch.fork_child import HELD_BACK, die_with_parent, run_child
from executor.batch.fork_protocol import (
    ENTRY_POINT,
    FolderRefused,
    fork_paired,
    open_log,
    receive,
    send,
    spawn_requests,
)

if TYPE_CHECKING:
    from executor.batch.fork_dispatch import Dispatcher


class Command:
    """The ``scenario_execution`` console script, imported from where it points (``target``, as
    :func:`~executor.batch.fork_protocol.command_target` found it; this package never imports the
    command layer): its ``main``,
    the path of its script, and its ``run_job(scenario, output_dir)`` when the command offers one
    (the same run without parsing the command line in every job)."""

    def __init__(self, target: str) -> None:
        import importlib
        import shutil

        module_name, _, attribute = target.partition(":")
        module = importlib.import_module(module_name)
        self.main = getattr(module, attribute)
        self.job = getattr(module, "run_job", None)
        name = ENTRY_POINT[0]
        self.script = shutil.which(name) or os.path.join(os.path.dirname(sys.executable), name)

    def run(self, argv: list[str]) -> None:
        """Run the command as ``argv`` (without the program name) asks; raises ``SystemExit`` like ``main``."""
        sys.argv = [self.script, *argv]
        if self.job is not None and len(argv) == 3 and argv[1] == "--output-dir":
            self.job(argv[0], argv[2])
        else:
            self.main()


#: A scenario importing every standard library, run once (as a ``.sce``) so that every module a run
#: imports lazily is loaded and every library parsed before the first fork.
_PROBE = ("import osc.types\nimport osc.helpers\nimport osc.standard\nimport osc.robotics\n\n"
          "scenario probe:\n    do serial:\n        log('x')\n        emit end\n")


def _probe_text() -> str:
    from coverage_engine.files.sce_writer import render_sce

    return render_sce("probe.osc", "0" * 64, ".", "probe", 0, {"probe.x": 1.0}, {"probe.x": "1.0"}, _PROBE)


def run_probe(command: Command, folder: str) -> None:
    """Run the command once on a probe variant of our own in ``folder``; raises if it fails.

    Only our own code runs: nothing from a scenario's folder or a plugin is imported here. What the
    probe run changes in this process (``sys.path``, ``sys.argv``, the standard streams) is put back.
    """
    import io

    saved = (list(sys.path), list(sys.argv), sys.stdout, sys.stderr)
    probe = os.path.join(folder, "probe0.sce")
    with open(probe, "w", encoding="utf-8") as handle:
        handle.write(_probe_text())
    sys.stdout = sys.stderr = io.StringIO()
    try:
        command.run([probe, "--output-dir", os.path.join(folder, "out")])
    except SystemExit as exc:
        if exc.code not in (0, None):
            raise RuntimeError(f"the probe run failed: {sys.stdout.getvalue()[-2000:]}") from None
    finally:
        sys.path[:], sys.argv[:] = saved[0], saved[1]
        sys.stdout, sys.stderr = saved[2], saved[3]


#: Probe runs before the server forks: CPython (3.11+) specializes a function's bytecode only once it
#: has run a few times (8 in 3.11); run that often here, so no job spends its time (and copies of
#: code objects' pages) doing it. Measured: a forked job's CPU 7.3 ms after one probe run, 6.4 after ten.
PRELOAD_RUNS = 10


class RunnerGone(Exception):
    """The runner closed its end before this server was ready: it ends without serving."""


def preload(command: Command, scratch: str, runner: socket.socket | None = None) -> None:
    """Run the probe in a folder under ``scratch`` (every lazily imported module loaded, every library
    parsed, the code a job runs specialized), then freeze what was made. Between two probe runs,
    :class:`RunnerGone` when ``runner``'s socket has become readable: the runner sends nothing before
    the server is ready, so that is its end closing (a command that found nothing to run, or died)."""
    import gc
    import tempfile

    with tempfile.TemporaryDirectory(prefix="preload_", dir=scratch) as folder:
        for _ in range(PRELOAD_RUNS):
            if runner is not None and select.select([runner], [], [], 0)[0]:
                raise RunnerGone
            run_probe(command, folder)
    gc.collect()
    gc.freeze()            # objects made so far are never scanned again, so the children do not copy them


class _Spare:
    """A forked child waiting for a job: its pid and the socket the job comes through."""

    def __init__(self, pid: int, sock: socket.socket) -> None:
        self.pid, self.sock = pid, sock


def _run_spare(sock: socket.socket, server: _Server) -> None:
    """In a spare child: warm up on the probe, wait for a job, run it (never returns)."""
    import shutil
    import tempfile

    try:
        os.setsid()                       # its own group from the start: the job's, and killable as one
        server.close_in_child()
        signal.set_wakeup_fd(-1)
        signal.pthread_sigmask(signal.SIG_BLOCK, HELD_BACK)
        for sig in (*HELD_BACK, signal.SIGCHLD):
            signal.signal(sig, signal.SIG_DFL)   # held back, not ignored: an ignored signal is lost
        folder = None
        try:
            folder = tempfile.mkdtemp(prefix="spare_", dir=server.scratch)
            run_probe(server.command, folder)
        except Exception:  # noqa: BLE001, S110 - warming up is best effort; the job runs all the same
            pass
        finally:
            if folder is not None:
                shutil.rmtree(folder, ignore_errors=True)
        request, fds = receive(sock, max_fds=1)
    except BaseException:  # noqa: BLE001 - a spare that cannot wait for a job just ends
        os._exit(1)
    sock.close()
    if request is None or len(fds) != 1:
        os._exit(0)                       # the server ended (or sent no output): nothing to run
    run_child(request, fds[0], server.close_in_child, server.command.run)


def _kill_group_and_leader(pid: int) -> None:
    """SIGKILL to the group of ``pid`` and to ``pid`` itself (whether or not it leads a group yet)."""
    for kill in (os.killpg, os.kill):
        try:
            kill(pid, signal.SIGKILL)
        except OSError:
            pass


class _Server:
    """The serving loop: requests from the runner, children reaped, all single-threaded.

    ``sock`` is the runner's socket, where the replies go. A forker of several
    (:mod:`executor.batch.fork_dispatch`) reads its requests from ``requests`` instead, the dispatcher's
    socket, and tells it there of every request it is done with (``{"free": 1}``: the job ended, or it
    could not start), so the dispatcher knows which forker has a slot free.
    """

    def __init__(self, sock: socket.socket, command: Command, scratch: str, keep_spare: bool = False,
                 limit: int = 0, requests: socket.socket | None = None) -> None:
        self.sock = sock
        self.requests = requests or sock               # where the requests come from
        self.keep_spare = keep_spare
        self.limit = limit                             # jobs at once (0: no limit)
        self.waiting: dict[str, tuple[dict, int | None]] = {}  # request id -> (request, output fd), in
                                                               # arrival order (None: it names its log)
        self.spare: _Spare | None = None
        self.scratch = scratch                         # the runner's folder for probe runs (it removes it)
        self.children: dict[int, str] = {}           # pid -> request id
        self.wake_read, self.wake_write = os.pipe()
        os.set_blocking(self.wake_write, False)
        os.set_blocking(self.wake_read, False)
        self.command = command

    def serve(self) -> None:
        signal.signal(signal.SIGCHLD, lambda *_: None)
        signal.set_wakeup_fd(self.wake_write)
        if self.keep_spare:
            self._new_spare()
        try:
            while True:
                ready, _, _ = select.select([self.requests.fileno(), self.wake_read], [], [])
                # the runner's messages before the reaping: a request withdrawn before a job was
                # stopped must be gone before that job's end starts the next waiting one
                if self.requests.fileno() in ready and not self._read_messages():
                    return
                if self.wake_read in ready:
                    try:
                        while os.read(self.wake_read, 512):
                            pass
                    except BlockingIOError:
                        pass
                self._reap()
        finally:
            self._end_children()

    def _read_messages(self) -> bool:
        """Handle every message the runner has sent so far; False when it closed its end."""
        while True:
            message, fds = receive(self.requests, max_fds=1)
            if message is None:
                return False
            if "withdraw" in message:
                self._withdraw(str(message["withdraw"]))
            else:
                for request, attached in spawn_requests(message, fds):
                    self._request(request, attached)
            if not select.select([self.requests.fileno()], [], [], 0)[0]:
                return True

    def _done_with(self) -> None:
        """A request ended (its job exited, or it could not start): a forker of several says so to its dispatcher."""
        if self.requests is not self.sock:
            send(self.requests, {"free": 1})

    def _end_children(self) -> None:
        """The runner is gone: so are its jobs, and the spare. Each is killed as a group and as a
        process: one forked a moment ago may not have its own group yet (found by a test that ended the
        server right after two starts: the group did not exist, and the job ran on)."""
        for _request, fd in self.waiting.values():
            if fd is not None:
                os.close(fd)
        self.waiting.clear()
        spare = self.spare
        for pid in self.children:
            _kill_group_and_leader(pid)
        if spare is not None:
            spare.sock.close()                   # a spare still warming up finds no job and ends
            _kill_group_and_leader(spare.pid)
            try:
                os.waitpid(spare.pid, 0)
            except ChildProcessError:
                pass

    def _request(self, request: dict, fds: list[int]) -> None:
        """A spawn request: it waits its turn behind earlier ones, and starts at once when a slot is free."""
        if len(fds) != 1 and (fds or not request.get("log")):
            for fd in fds:
                os.close(fd)
            send(self.sock, {"id": request.get("id"), "event": "failed", "reason": "no output descriptor"})
            self._done_with()
            return
        self.waiting[str(request.get("id"))] = (request, fds[0] if fds else None)
        self._start_waiting()

    def _start_waiting(self) -> None:
        """Start waiting requests, oldest first, while fewer than ``limit`` jobs run."""
        while self.waiting and not (self.limit and len(self.children) >= self.limit):
            request_id = next(iter(self.waiting))
            request, fd = self.waiting.pop(request_id)
            if fd is None:
                try:
                    fd = open_log(request)
                except Exception as exc:  # noqa: BLE001 - one request must not end the server and its jobs
                    send(self.sock, {"id": request_id, "event": "failed", **_unprepared(request, exc)})
                    self._done_with()
                    continue
            self._spawn(request, fd)

    def _withdraw(self, request_id: str) -> None:
        waiting = self.waiting.pop(request_id, None)
        if waiting is not None:
            if waiting[1] is not None:
                os.close(waiting[1])
            send(self.sock, {"id": request_id, "event": "withdrawn"})

    def _spawn(self, request: dict, output_fd: int) -> None:
        pid = self._hand_to_spare(request, output_fd)
        if pid is None:
            parent = os.getpid()
            try:
                pid = os.fork()
            except OSError as exc:
                os.close(output_fd)
                send(self.sock, {"id": request["id"], "event": "failed", "reason": f"fork: {exc.strerror}"})
                self._done_with()
                return
            if pid == 0:
                die_with_parent(parent)
                run_child(request, output_fd, self.close_in_child, self.command.run)
        os.close(output_fd)
        self.children[pid] = request["id"]
        send(self.sock, {"id": request["id"], "event": "started", "pid": pid, "at": time.monotonic()})
        if self.keep_spare and self.spare is None:
            self._new_spare()

    def _hand_to_spare(self, request: dict, output_fd: int) -> int | None:
        """Give the job to the spare (its pid), or None when there is none or it is gone."""
        spare, self.spare = self.spare, None
        if spare is None:
            return None
        try:
            send(spare.sock, request, [output_fd])
        except OSError:
            spare.sock.close()
            return None
        spare.sock.close()
        return spare.pid

    def _new_spare(self) -> None:
        """Fork a spare child that warms itself up and waits for a job (see the module's doc)."""
        parent = os.getpid()
        try:
            pid, sock = fork_paired()
        except OSError:
            return
        if pid == 0:
            die_with_parent(parent)
            _run_spare(sock, self)
        self.spare = _Spare(pid, sock)

    def close_in_child(self) -> None:
        """What a job must not keep of the server: its socket, wake-up pipe, the spare's socket and the
        output files of the requests still waiting (another job's log held open)."""
        if self.sock.fileno() < 0:
            return                              # a spare closed them when it was forked
        self.sock.close()
        self.requests.close()
        os.close(self.wake_read)
        os.close(self.wake_write)
        if self.spare is not None:
            self.spare.sock.close()
        for _request, fd in self.waiting.values():
            if fd is not None:
                os.close(fd)
        self.waiting.clear()

    def _reap(self) -> None:
        while self.children:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return
            if pid == 0:
                return
            if self.spare is not None and pid == self.spare.pid:   # it died before it had a job
                self.spare.sock.close()
                self.spare = None
                continue
            job = self.children.pop(pid, None)
            if job is not None:
                ended = time.monotonic()
                self._start_waiting()          # the slot's next job first, then the news
                send(self.sock, {"id": job, "event": "exited", "pid": pid, "status": status, "at": ended})
                self._done_with()


def _unprepared(request: dict, exc: Exception) -> dict:
    """What the ``failed`` reply says of a request whose folder or log could not be prepared: the error
    (``errno``, whether the folder was refused) and its reason."""
    if not isinstance(exc, OSError):
        return {"reason": f"internal error while preparing the job: {exc!r}"}
    refused = isinstance(exc, FolderRefused)
    return {"errno": exc.errno, "folder": refused,
            "reason": f"cannot prepare the job: {exc.strerror}" if refused else
            f"cannot open its log {request['log']}: {exc.strerror or exc}"}


def serve(fd: int, target: str, scratch: str, keep_spare: bool = False, limit: int = 0,
          forkers: int = 1) -> None:
    """Entry of the server process: ``fd`` is its end of the socket pair; ``target`` the command's
    ``module:function`` (:func:`~executor.batch.fork_protocol.command_target`); ``scratch`` a private folder of the runner's for the
    probe runs (the runner removes it, or its watchdog after a ``kill -9``); ``keep_spare``: keep a warm
    spare child (the runner has a core to spare); ``limit``: jobs at once, more requests wait;
    ``forkers``: processes that fork the jobs (more than one: :mod:`executor.batch.fork_dispatch`)."""
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_IGN)          # the runner decides; its children are in their own groups
    signal.pthread_sigmask(signal.SIG_BLOCK, HELD_BACK)   # and inherit them blocked (see fork_child.run_child)
    sock = socket.socket(fileno=fd)
    dispatcher: Dispatcher | None = None
    try:
        try:
            command = Command(target)
            preload(command, scratch, sock)
            if forkers > 1:
                from executor.batch.fork_dispatch import Dispatcher

                dispatcher = Dispatcher(sock, limit)
                dispatcher.start_forkers(forkers, lambda requests: _Server(sock, command, scratch, keep_spare,
                                                                           requests=requests).serve())
            server: _Server | Dispatcher = dispatcher or _Server(sock, command, scratch, keep_spare, limit)
        except RunnerGone:
            raise SystemExit(0) from None
        except BaseException as exc:  # noqa: BLE001 - say why to the runner, then end
            _tell(sock, {"event": "unavailable", "reason": f"{type(exc).__name__}: {exc}"})
            raise SystemExit(1) from None
        if not _tell(sock, {"event": "ready", "pid": os.getpid()}):
            raise SystemExit(0)                     # the runner went away while this one was preloading
        server.serve()
    finally:
        if dispatcher is not None:
            dispatcher.end()                        # its forkers gone, and their spares with them
        # every child that writes to the scratch folder (a spare warming up) has ended: the runner removes
        # the folder too, but one that has gone (killed before its watchdog knew of the folder) cannot
        import shutil

        shutil.rmtree(scratch, ignore_errors=True)


def _tell(sock: socket.socket, message: dict) -> bool:
    """Send ``message`` to the runner; False when it has gone."""
    try:
        send(sock, message)
    except OSError:
        return False
    return True
