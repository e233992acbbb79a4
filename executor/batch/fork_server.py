"""The fork server of the built-in runner: a warm process that forks one child per job.

Started once per worker (``python -c …serve()``), it imports the ``scenario_execution`` command and
the runtime, parses the standard ``.osc`` libraries, and then only forks: each request becomes a
child that turns itself into what ``scenario_execution SCENARIO --output-dir OUTPUT_DIR`` would have
been as a fresh process — its own session and process group, stdin from ``/dev/null``, stdout and
stderr into the file descriptor the runner sent, the runner's working directory and environment
plus the job's marker, default signal handling, fresh ``sys.std*`` objects buffered as a new
interpreter's would be — and runs the command's ``main()``. So a job costs a fork and the scenario,
not an interpreter start, and its files, output and exit status are those of the launched command.

Nothing of a scenario ever runs in the server: plugins, external methods and the scenario folder's
modules are imported by the child that needs them, and die with it, so a job that crashes, leaks,
changes global state or hangs cannot touch the next one.

Protocol (a Unix socket pair, one message per ``sendmsg``): the runner sends ``spawn`` requests as
JSON with the job's output file descriptor attached; the server answers ``started`` (the child's pid)
or ``failed`` (why not), and ``exited`` with the raw wait status when the child ends. The server
reaps its children and ends when the runner closes its end (it died or is done): it then kills
the process groups of the children still running, so no job outlives its runner.
"""

from __future__ import annotations

import array
import json
import os
import select
import signal
import socket
import sys

#: Largest request or reply, in bytes.
MAX_MESSAGE = 64 * 1024

#: What the runner asks the server to run: the console script of the command (name, group).
ENTRY_POINT = ("scenario_execution", "console_scripts")


def send(sock: socket.socket, message: dict, fds: list[int] | None = None) -> None:
    """One JSON message, with file descriptors attached when given."""
    data = json.dumps(message).encode()
    if fds:
        sock.sendmsg([data], [(socket.SOL_SOCKET, socket.SCM_RIGHTS, array.array("i", fds))])
    else:
        sock.sendall(data)


def receive(sock: socket.socket, max_fds: int = 0) -> tuple[dict | None, list[int]]:
    """The next message (None when the other end closed) and the descriptors that came with it."""
    fds = array.array("i")
    data, ancillary, _flags, _addr = sock.recvmsg(MAX_MESSAGE, socket.CMSG_SPACE(max_fds * fds.itemsize)
                                                  if max_fds else 0)
    for level, kind, payload in ancillary:
        if level == socket.SOL_SOCKET and kind == socket.SCM_RIGHTS:
            fds.frombytes(payload[:len(payload) - len(payload) % fds.itemsize])
    if not data:
        for fd in fds:
            os.close(fd)
        return None, []
    return json.loads(data), list(fds)


# ------------------------------------------------------------------------------ in the server

def _entry_point():
    """The ``main`` of the ``scenario_execution`` console script (found by name: this package never
    imports the command layer) and the path of its script."""
    import shutil
    from importlib.metadata import entry_points

    name, group = ENTRY_POINT
    found = [ep for ep in entry_points(group=group) if ep.name == name]
    if not found:
        raise RuntimeError(f"the console script {name!r} is not installed")
    script = shutil.which(name) or os.path.join(os.path.dirname(sys.executable), name)
    return found[0].load(), script


#: A scenario importing every standard library, run once (as a ``.sce``) so that every module a run
#: imports lazily is loaded and every library parsed before the first fork.
_PROBE = ("import osc.types\nimport osc.helpers\nimport osc.standard\nimport osc.robotics\n\n"
          "scenario probe:\n    do serial:\n        log('x')\n        emit end\n")


def preload(main, script: str) -> None:
    """Run the command once on a probe variant of our own, then freeze what was made.

    Only our own code runs: nothing from a scenario's folder or a plugin is imported here. What the
    probe run changes in this process (``sys.path``, ``sys.argv``, the standard streams) is put back.
    """
    import gc
    import io
    import tempfile

    from coverage_engine.files.sce import render_sce

    saved = (list(sys.path), list(sys.argv), sys.stdout, sys.stderr)
    with tempfile.TemporaryDirectory(prefix="scenario_fork_server_") as folder:
        probe = os.path.join(folder, "probe0.sce")
        with open(probe, "w", encoding="utf-8") as handle:
            handle.write(render_sce("probe.osc", "0" * 64, ".", "probe", 0, {"probe.x": 1.0}, {"probe.x": "1.0"},
                                    _PROBE))
        sys.argv = [script, probe, "--output-dir", os.path.join(folder, "out")]
        sys.stdout = sys.stderr = io.StringIO()
        try:
            main()
        except SystemExit as exc:
            if exc.code not in (0, None):
                raise RuntimeError(f"the probe run failed: {sys.stdout.getvalue()[-2000:]}") from None
        finally:
            sys.path[:], sys.argv[:] = saved[0], saved[1]
            sys.stdout, sys.stderr = saved[2], saved[3]
    gc.collect()
    gc.freeze()            # objects made so far are never scanned again, so the children do not copy them


def _fresh_stdio() -> None:
    """``sys.stdin/stdout/stderr`` on fds 0-2 as a new interpreter makes them (buffering and all)."""
    import io

    unbuffered = bool(os.environ.get("PYTHONUNBUFFERED"))
    old = {name: getattr(sys, name) for name in ("stdin", "stdout", "stderr")}

    def stream(fd: int, mode: str, like, line_buffering: bool):
        raw = io.FileIO(fd, mode, closefd=False)
        if mode == "r":
            return io.TextIOWrapper(io.BufferedReader(raw), encoding=like.encoding, errors=like.errors)
        buffered = io.BufferedWriter(raw)
        return io.TextIOWrapper(buffered, encoding=like.encoding, errors=like.errors,
                                line_buffering=line_buffering or os.isatty(fd), write_through=unbuffered)

    for fd, name, line_buffering in ((0, "stdin", False), (1, "stdout", False), (2, "stderr", True)):
        fresh = stream(fd, "r" if fd == 0 else "w", old[name], line_buffering)
        setattr(sys, name, fresh)          # the job's own streams, also as sys.__stdin__ & co.
        setattr(sys, f"__{name}__", fresh)


def _exit_code(exc: SystemExit) -> int:
    """What the interpreter would exit with for ``SystemExit`` (``None`` 0, a text printed and 1)."""
    code = exc.code
    if code is None:
        return 0
    if isinstance(code, int):
        return code & 0xFF
    print(code, file=sys.stderr)
    return 1


def _run_child(request: dict, output_fd: int, server: _Server) -> None:
    """In the forked child: become the launched command, run it, never return."""
    code = 1
    try:
        os.setsid()
        server.close_in_child()
        for sig in (signal.SIGTERM, signal.SIGCHLD, signal.SIGHUP, signal.SIGQUIT):
            signal.signal(sig, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGPIPE, signal.SIG_IGN)         # as the interpreter sets it at start
        signal.set_wakeup_fd(-1)
        null = os.open(os.devnull, os.O_RDONLY)
        os.dup2(null, 0)
        os.dup2(output_fd, 1)
        os.dup2(output_fd, 2)
        for fd in (null, output_fd):
            if fd > 2:
                os.close(fd)
        os.chdir(request["cwd"] or ".")
        os.environ.update(request["env"])
        _fresh_stdio()
        sys.argv = [server.script, *request["argv"][1:]]
        try:
            server.main()
            code = 0
        except SystemExit as exc:
            code = _exit_code(exc)
        except KeyboardInterrupt:
            code = 128 + signal.SIGINT
        except BaseException:  # noqa: BLE001 - what the interpreter would print for an uncaught error
            sys.excepthook(*sys.exc_info())
            code = 1
        import atexit

        atexit._run_exitfuncs()
    finally:
        for name in ("stdout", "stderr"):
            try:
                getattr(sys, name).flush()
            except Exception:  # noqa: BLE001, S110 - the output may be gone; the exit status still counts
                pass
        os._exit(code)


class _Server:
    """The serving loop: requests from the runner, children reaped, all single-threaded."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.children: dict[int, str] = {}           # pid -> request id
        self.wake_read, self.wake_write = os.pipe()
        os.set_blocking(self.wake_write, False)
        os.set_blocking(self.wake_read, False)
        self.main, self.script = _entry_point()

    def serve(self) -> None:
        signal.signal(signal.SIGCHLD, lambda *_: None)
        signal.set_wakeup_fd(self.wake_write)
        try:
            while True:
                ready, _, _ = select.select([self.sock.fileno(), self.wake_read], [], [])
                if self.wake_read in ready:
                    try:
                        while os.read(self.wake_read, 512):
                            pass
                    except BlockingIOError:
                        pass
                    self._reap()
                if self.sock.fileno() in ready:
                    message, fds = receive(self.sock, max_fds=1)
                    if message is None:
                        return
                    self._spawn(message, fds)
                self._reap()
        finally:
            for pid in list(self.children):          # the runner is gone: so are its jobs
                try:
                    os.killpg(pid, signal.SIGKILL)
                except OSError:
                    pass

    def _spawn(self, request: dict, fds: list[int]) -> None:
        if len(fds) != 1:
            for fd in fds:
                os.close(fd)
            send(self.sock, {"id": request.get("id"), "event": "failed", "reason": "no output descriptor"})
            return
        try:
            pid = os.fork()
        except OSError as exc:
            os.close(fds[0])
            send(self.sock, {"id": request["id"], "event": "failed", "reason": f"fork: {exc.strerror}"})
            return
        if pid == 0:
            _run_child(request, fds[0], self)
        os.close(fds[0])
        self.children[pid] = request["id"]
        send(self.sock, {"id": request["id"], "event": "started", "pid": pid})

    def close_in_child(self) -> None:
        """What a job must not keep of the server: its socket and wake-up pipe."""
        self.sock.close()
        os.close(self.wake_read)
        os.close(self.wake_write)

    def _reap(self) -> None:
        while self.children:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return
            if pid == 0:
                return
            job = self.children.pop(pid, None)
            if job is not None:
                send(self.sock, {"id": job, "event": "exited", "pid": pid, "status": status})


def serve(fd: int) -> None:
    """Entry of the server process: ``fd`` is its end of the socket pair."""
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_IGN)          # the runner decides; its children are in their own groups
    sock = socket.socket(fileno=fd)
    try:
        server = _Server(sock)
        preload(server.main, server.script)
    except BaseException as exc:  # noqa: BLE001 - say why to the runner, then end
        send(sock, {"event": "unavailable", "reason": f"{type(exc).__name__}: {exc}"})
        raise SystemExit(1) from None
    send(sock, {"event": "ready", "pid": os.getpid()})
    server.serve()
