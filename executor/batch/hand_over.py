"""Hand-over to the built-in runner's fork server, and how many jobs a worker holds at once.

:class:`HandOver` starts the worker's fork server on the first built-in job (again should it end),
with as many forking processes as its slots call for (:func:`~executor.batch.builtin_runner.forkers_for`),
numbers the jobs so that they reach it in claim order (:class:`~executor.batch.job_run.StartOrder`),
and says how many jobs the worker holds: its slots, and in a single-host batch of the built-in
runner :data:`AHEAD_PER_SLOT` more per slot (one per slot where every job has a thread of its own:
``-j 1`` showing the output as it runs), handed to the fork server ahead. The server keeps each until a slot is free
and starts it the moment a job ends, so no slot waits while the worker records a result and claims
the next job (measured, 1,000 trivial jobs at -j 2: 1.36 slots busy on average without). Launched
commands, a ``worker`` (jobs it holds ahead would wait behind its busy slots while other hosts
idle), ``--halt-on-failure`` (a job handed ahead would start before the failure is known) and
``--post-run`` (the next job would start while the last one's hooks still run) hold no more than
their slots.

The command line may launch the server before it knows the batch
(:func:`~executor.batch.worker_server.start_early`), so that the
server's imports and preload overlap its own; the worker then adopts that server for its first job when
it was launched as the worker would start one (its slots and mark), and closes it otherwise.

The worker's loop need not read the server's replies the moment they come: while the server holds
enough jobs to keep every slot busy, the loop lets them gather for up to :data:`LINGER` and reads them
all at one wake-up (:meth:`HandOver.linger`). On a shared 2-core VM each wake-up of the batch process
cost about as much as one job's own work (caches and the scheduler, not our code: the same judging ran
four times faster in a tight loop), so the server is handed :data:`AHEAD_PER_SLOT` jobs per slot ahead,
enough for the gathering not to leave a slot idle (measured side by side, 2,000 trivial jobs at -j 2:
1.23-1.46 ms of the batch process's CPU per job before, 0.87-1.08 ms after; the wall time no longer).
The server stamps each start and end with its clock (``time.monotonic``), so a job's times and its
``--timeout`` do not depend on when the loop read them. The gathering is bounded by the socket too
(:data:`REPLY_ROOM`): the server never waits to send a reply. After a ``kill -9`` the jobs held ahead
go back to the queue uncharged (the store has no start recorded for them, see
``QueueStore._reclaim``); the depth is bounded all the same, as those jobs wait for a ``--resume`` or
for another worker's sweep.

A single-host batch also claims in chunks (:meth:`HandOver.claim_limit`): at least
:data:`CLAIM_CHUNK` jobs per claim, held by the worker (claimed, not started) until a slot frees, so
one store transaction claims many jobs (measured on 2 cores at -j 2: one claim per job was the
largest share of the batch process's own CPU in its loop). A job held so is ``running`` in the store
with its lease kept alive, exactly like a job handed to the fork server ahead: a runner killed
meanwhile leaves it to ``--resume`` (or another worker) to run, a stopped one gives it back
(``queued``). Not with ``--halt-on-failure`` or ``--repeat until-fail`` (the jobs held would start
after the failure that should have stopped them) and not for a ``worker`` (other hosts would idle).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from executor.batch.builtin_runner import ForkServer, forkers_for
from executor.batch.fork_errors import ForkServerError
from executor.batch.job_run import StartOrder
from executor.batch.worker_server import worker_fork_server
from store.jobs import Batch

#: Jobs a single-host run claims in one transaction at least (more when it holds more than that).
CLAIM_CHUNK = 16

#: Jobs a single-host built-in batch hands the fork server ahead, per slot, when the worker's loop drives
#: them (no thread waits per job): at the rate one core forks trivial jobs, enough for every slot to stay
#: busy while the loop lets the replies gather for :data:`LINGER`.
AHEAD_PER_SLOT = 8

#: Longest the worker's loop lets the fork server's replies gather before it reads them (seconds).
LINGER = 0.05

#: Recent starts the rate of starts is taken over (for :meth:`HandOver.linger`).
RATE_WINDOW = 32

#: Replies of the server that may gather unread (a start and an end per job): well within what the
#: socket holds (about 270 of them with Linux's default buffer), so the server never waits to send one.
REPLY_ROOM = 128


class HandOver:
    """The fork server of one worker (``runner_id``: its mark for the watchdog) and its start order."""

    def __init__(self, runner_id: str, slots: int, *, ahead_allowed: bool,
                 on_scratch: Callable[[str], None] | None = None, forkers: int | None = None,
                 early: ForkServer | None = None, threaded: bool = False) -> None:
        """``threaded``: every job runs in a thread of its own (``-j 1`` showing the output), which waits
        for its start while the server holds it: then only as many jobs as slots are held ahead."""
        self.runner_id = runner_id
        self.slots = slots
        self.forkers = forkers_for(slots) if forkers is None else forkers   # processes forking the jobs
        self._early = early                        # a server launched before the batch was known (start_early)
        self.ahead_allowed = ahead_allowed         # the single-host run may hand jobs over ahead
        self.on_scratch = on_scratch               # the watchdog removes the server's scratch folder
        self.order = StartOrder()
        self._per_slot = 1 if threaded else AHEAD_PER_SLOT
        self._starts: deque[float] = deque(maxlen=RATE_WINDOW)   # when the latest jobs started (monotonic)
        self._server: ForkServer | None = None
        self._ahead: int | None = None             # None until the first batch decided it
        self._chunk = 0                            # jobs claimed at once at least (0: what is free)

    def launcher(self) -> ForkServer:
        """The fork server, started on the first job that needs it (again if it ended);
        :class:`~executor.batch.fork_errors.ForkServerError` when it cannot start."""
        if self._server is None or not self._server.alive:
            if self._server is not None:
                self._server.close()
                self._server = None
            early, self._early = self._early, None
            self._server = self._new_server() if early is None else self._adopt(early)
        return self._server

    def _new_server(self) -> ForkServer:
        return worker_fork_server(self.runner_id, self.slots, self.forkers, self.on_scratch).start()

    def _adopt(self, early: ForkServer) -> ForkServer:
        """The server launched early, once ready, when it was launched as this worker would start one; else
        it is closed and a new one started."""
        if early.setup != worker_fork_server(self.runner_id, self.slots, self.forkers).setup:
            early.close()
            return self._new_server()
        if self.on_scratch is not None and early.scratch is not None:
            self.on_scratch(early.scratch)
        try:
            ready = early.wait_ready()
        except ForkServerError:
            ready = None                           # it ended while the command started: a new one says why
        if ready is None or early.proc is None or early.proc.poll() is not None:
            early.close()
            return self._new_server()
        return ready

    def send_submitted(self) -> None:
        """Send the fork server the requests submitted to go together (see :meth:`ForkServer.submit`)."""
        if self._server is not None:
            self._server.send_submitted()

    @property
    def server(self) -> ForkServer | None:
        """The fork server while one runs (the worker's loop reads its replies), else None."""
        return self._server if self._server is not None and self._server.alive else None

    def close(self) -> None:
        """Stop the fork server (it kills the jobs still running), if there is one, and one launched early
        that no job needed."""
        for server in (self._server, self._early):
            if server is not None:
                server.close()
        self._server = self._early = None

    def decide(self, batch: Batch) -> int:
        """The jobs to hold, deciding on hand-over ahead from the (single) batch's command and options."""
        if self._ahead is None:
            options = batch.options
            ahead = self.ahead_allowed and not batch.command and not options.halt_on_failure \
                and not options.post_run and not options.until_fail
            self._ahead = self._per_slot * self.slots if ahead else 0
            chunked = self.ahead_allowed and not options.halt_on_failure and not options.until_fail
            self._chunk = max(CLAIM_CHUNK, self.holding()) if chunked else 0
        return self.holding()

    def claim_limit(self, free: int) -> int:
        """How many jobs to claim when ``free`` may start now: a chunk in a single-host batch (see the module doc)."""
        return max(free, self._chunk)

    def holding(self) -> int:
        """The jobs this worker may hold now (its slots until a batch decided on more)."""
        return self.slots + (self._ahead or 0)

    def started(self, at: float) -> None:
        """A job started at ``at`` (``time.monotonic``): the rate of starts :meth:`linger` goes by."""
        self._starts.append(at)

    def linger(self, queued: int, now: float) -> float:
        """Seconds the worker's loop may leave the server's replies unread, ``queued`` jobs waiting there
        for a slot: none unless jobs are handed over ahead and those waiting keep every slot busy for twice
        as long at the rate jobs started lately; at most :data:`LINGER`, and no longer than it takes
        :data:`REPLY_ROOM` replies to come at that rate."""
        if not self._ahead or queued < self.slots or len(self._starts) < 2:
            return 0.0
        span = now - self._starts[0]
        if span <= 0.0:
            return 0.0
        rate = len(self._starts) / span            # starts per second, lately
        return min(LINGER, queued / rate / 2.0, REPLY_ROOM / 2.0 / rate)
