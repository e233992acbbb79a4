"""The fork server a worker uses, described once, and its launch before the batch is known.

:func:`worker_fork_server` says how a worker with so many slots starts its server (its mark, a spare
when a core is left over, its forkers); :class:`~executor.batch.hand_over.HandOver` starts it so, and
compares an early server's :attr:`~executor.batch.builtin_runner.ForkServer.setup` with it before
adopting one. :func:`start_early` is that early launch: the command line calls it before it imports
the store and reads the inputs.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass

from executor.batch.builtin_runner import ForkServer, forkers_for, spare_cores
from executor.batch.fork_errors import ForkServerError
from executor.children.process import RUNNER_ENV
from store.jobs import WorkerIdentity


def fork_server_environment(runner_id: str) -> dict[str, str]:
    """The fork server's environment: this process's, and the runner's mark (see the watchdog)."""
    return {**os.environ, RUNNER_ENV: runner_id}


def worker_fork_server(runner_id: str, slots: int, forkers: int | None = None,
                       on_scratch: Callable[[str], None] | None = None) -> ForkServer:
    """The fork server (not started yet) of the worker ``runner_id`` with ``slots``: its mark in the
    environment, a spare when a core is left over, no more jobs at once than its slots, and as many
    forkers as they call for (unless ``forkers`` says)."""
    return ForkServer(fork_server_environment(runner_id), keep_spare=spare_cores(slots), limit=slots,
                      forkers=forkers_for(slots) if forkers is None else forkers, on_scratch=on_scratch)


@dataclass(frozen=True)
class EarlyServer:
    """A fork server launched before its batch was known, and the identity of the worker it is for (its
    mark is in the server's environment, so that worker must be this one)."""

    identity: WorkerIdentity
    server: ForkServer


def start_early(slots: int) -> EarlyServer | None:
    """Launch the fork server a worker with ``slots`` would start, before the batch is known (see
    :class:`~executor.batch.hand_over.HandOver`'s ``early``): the command line does it before it
    imports the store and reads the inputs, so the server's imports and preload (0.15 s on the 2-core
    VM) go on meanwhile on another core. None when it cannot be launched (the worker then starts one,
    and says why)."""
    identity = WorkerIdentity.current()
    try:
        return EarlyServer(identity, worker_fork_server(identity.id, slots).launch())
    except ForkServerError:
        return None
