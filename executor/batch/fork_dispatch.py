"""Several processes fork the jobs: the fork server, once warm, becomes a dispatcher of forkers.

Why: forking a warm interpreter is the fork server's work for every job, and it is not small. Measured
on the project's 2-core VM (``benchmarks/bench_batch_process.py``, 2,000 trivial jobs): the server's own
CPU was 1.3-1.8 ms a job, about twice the batch process's, nine tenths of it in the kernel (the
``fork`` copying its page tables, then a copy of every page the server writes while the child still
shares it). One process forking every job caps a worker at about 600-750 jobs a second whatever its
``-j``, which is below what 16 cores run of short jobs.

So with many slots (:func:`~executor.batch.builtin_runner.forkers_for`) the server, after its preload,
forks ``count`` copies of itself (warm, with nothing loaded twice), each a
:class:`~executor.batch.fork_server._Server` that forks its share of the jobs, and stays as their
dispatcher:

* it reads the runner's requests and keeps the waiting ones in arrival order; no more than ``limit``
  jobs run at once over all forkers, and each next request goes to the forker running the fewest
  (never blocking on one whose socket is full: it waits here until that forker has room);
* a ``withdraw`` of a request that still waits is answered here (``withdrawn``); one handed to a
  forker has started, and the runner stops it as any other;
* the forkers send their replies (``started``, ``failed``, ``exited``) straight to the runner on the
  same socket (a ``SOCK_SEQPACKET`` message is delivered whole, never mixed with another's), and tell
  the dispatcher on their own socket when they are done with a request, so it hands over the next.

The runner sees one server and one conversation. When the runner closes its end, the dispatcher
closes the forkers' sockets: each kills its running jobs and ends, and the dispatcher waits for them.
A forker that dies ends the dispatcher the same way, so the runner sees its server gone, as when a
single server dies: the jobs it knew of are killed and the waiting ones fail.
"""

from __future__ import annotations

import os
import select
import socket
import sys
from collections import OrderedDict
from collections.abc import Callable

from executor.batch.fork_protocol import fork_paired, receive, send, spawn_requests


class Forker:
    """One forking copy of the server: its pid, the socket to it, the jobs it was given and not done
    with, and whether its socket had no room for the last request (the dispatcher waits until it has)."""

    def __init__(self, pid: int, sock: socket.socket) -> None:
        self.pid, self.sock, self.running, self.full = pid, sock, 0, False


class Dispatcher:
    """The server's loop when several processes fork (see the module doc); ``sock`` is the runner's socket."""

    def __init__(self, sock: socket.socket, limit: int) -> None:
        self.sock = sock
        self.limit = limit                                  # jobs at once over all forkers (0: no limit)
        self.forkers: list[Forker] = []
        self.waiting: OrderedDict[str, tuple[dict, list[int]]] = OrderedDict()   # id -> (request, descriptors)

    def start_forkers(self, count: int, serve_forker: Callable[[socket.socket], None]) -> None:
        """Fork ``count`` forkers, each running ``serve_forker`` on its end of a socket pair to this
        process (it returns when that socket closes, and the forker ends). Raises ``OSError`` when one
        cannot be forked (those already forked end with this process)."""
        for _ in range(count):
            pid, sock = fork_paired()
            if pid == 0:
                code = 1
                try:
                    for forker in self.forkers:              # the other forkers' sockets are not this one's
                        forker.sock.close()
                    serve_forker(sock)
                    code = 0
                except BaseException:  # noqa: BLE001 - said on the runner's stderr, as the server's own end would be
                    sys.excepthook(*sys.exc_info())
                    sys.stderr.flush()
                finally:
                    os._exit(code)
            self.forkers.append(Forker(pid, sock))

    def serve(self) -> None:
        """Dispatch until the runner closes its end or a forker ends; then end the forkers and wait for them."""
        try:
            while True:
                ready, room, _ = select.select([self.sock, *(forker.sock for forker in self.forkers)],
                                               [forker.sock for forker in self.forkers if forker.full], [])
                if self.sock in ready and not self._read_requests():
                    return
                for forker in self.forkers:
                    if forker.sock in ready and not self._read_notes(forker):
                        return
                    if forker.sock in room:
                        forker.full = False
                if not self._dispatch():
                    return
        finally:
            self.end()

    def _read_requests(self) -> bool:
        """Every message the runner has sent so far; False when it closed its end."""
        while True:
            try:
                message, fds = receive(self.sock, max_fds=1, flags=socket.MSG_DONTWAIT)
            except BlockingIOError:
                return True
            if message is None:
                return False
            if "withdraw" in message:
                self._withdraw(str(message["withdraw"]))
            else:
                for request, attached in spawn_requests(message, fds):
                    self.waiting[str(request.get("id"))] = (request, attached)

    def _read_notes(self, forker: Forker) -> bool:
        """What ``forker`` says (a request done with); False when it has ended."""
        while True:
            try:
                message, _fds = receive(forker.sock, flags=socket.MSG_DONTWAIT)
            except BlockingIOError:
                return True
            except OSError:
                return False
            if message is None:
                return False
            forker.running -= int(message.get("free", 0))

    def _withdraw(self, request_id: str) -> None:
        waiting = self.waiting.pop(request_id, None)
        if waiting is not None:
            for fd in waiting[1]:
                os.close(fd)
            send(self.sock, {"id": request_id, "event": "withdrawn"})

    def _dispatch(self) -> bool:
        """Hand the waiting requests, oldest first, to the least busy forkers while fewer than ``limit``
        run; False when a forker has ended (it cannot be sent to).

        Never waits for a forker: one whose socket is full (it is busy reaping a burst of ends, and
        sending the notes this process must read) keeps the request waiting here until it has room.
        Waiting for it would stop this process reading those notes, and both would wait for good."""
        while self.waiting and not (self.limit and sum(f.running for f in self.forkers) >= self.limit):
            open_forkers = [forker for forker in self.forkers if not forker.full]
            if not open_forkers:
                return True
            forker = min(open_forkers, key=lambda f: f.running)
            request_id, (request, fds) = self.waiting.popitem(last=False)
            try:
                send(forker.sock, request, fds, socket.MSG_DONTWAIT)
            except BlockingIOError:
                self.waiting[request_id] = (request, fds)
                self.waiting.move_to_end(request_id, last=False)
                forker.full = True
                continue
            except OSError:
                for fd in fds:
                    os.close(fd)
                return False
            for fd in fds:
                os.close(fd)
            forker.running += 1
        return True

    def end(self) -> None:
        """Close what waits and the forkers' sockets (each then kills its jobs and ends); wait for them.
        Again, it does nothing more."""
        for _request, fds in self.waiting.values():
            for fd in fds:
                os.close(fd)
        self.waiting.clear()
        for forker in self.forkers:
            forker.sock.close()
        for forker in self.forkers:
            try:
                os.waitpid(forker.pid, 0)
            except ChildProcessError:
                pass
