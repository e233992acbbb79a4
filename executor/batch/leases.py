"""The worker's leases: keep its own alive, take back the jobs of holders that died or went silent.

A claim holds a job for ``lease`` seconds; :meth:`LeaseKeeper.heartbeat` extends every lease this
worker holds (every quarter lease), gives back jobs the store says it holds but it never heard of
(a claim whose reply was lost), and names the jobs whose lease was taken over (their runs are
stopped: another worker runs them now). :meth:`LeaseKeeper.sweep` queues again the jobs of a dead
runner on this host at once (its process is gone) and those of any holder whose lease expired,
and ends the orphaned child of a dead runner's job, if that process group is still the job's.
"""

from __future__ import annotations

from collections.abc import Iterable

from executor.batch.job_run import job_marker
from executor.children.process import end_orphan_group, process_alive
from store.jobs import Reclaimed, WorkerIdentity
from store.queue import QueueStore


class LeaseKeeper:
    """Heartbeats and sweeps of one worker (``batch_id``: only that batch; None: the shared batches)."""

    def __init__(self, store: QueueStore, identity: WorkerIdentity, *, lease: float, max_lost: int,
                 batch_id: int | None) -> None:
        self.store = store
        self.identity = identity
        self.lease = lease
        self.max_lost = max_lost
        self.batch_id = batch_id
        #: Seconds between two heartbeats, and between two sweeps.
        self.every = max(0.05, lease / 4)

    def heartbeat(self, held: Iterable[int]) -> set[int]:
        """Extend the leases; give back jobs held in the store but not in ``held``; returns those of
        ``held`` the store no longer gives this worker (lost: another worker took them over)."""
        mine = set(held)
        in_store = self.store.heartbeat(self.identity, self.lease)
        phantoms = in_store - mine
        if phantoms:                          # claimed, but the reply never reached us: give them back
            self.store.release(self.identity, phantoms)
        return mine - in_store

    def sweep(self) -> list[Reclaimed]:
        """Take back jobs of dead holders on this host at once, and of any holder whose lease expired."""
        reclaimed: list[Reclaimed] = []
        dead = {j.worker_id for j in self.store.running(self.batch_id, shared_only=self.batch_id is None)
                if self.identity.same_node(j.worker_id) and j.worker_id != self.identity.id
                and not process_alive(j.worker_pid)}
        for worker_id in sorted(w for w in dead if w):
            reclaimed += self.store.reclaim_worker(worker_id, "the runner holding it ended without a result",
                                                   max_lost=self.max_lost)
        reclaimed += self.store.reclaim_expired(self.max_lost)
        for item in reclaimed:
            if item.child_pid and self.identity.same_node(item.worker_id) and item.worker_id != self.identity.id:
                # the orphaned child of a dead runner must not run on (if that group is still it)
                end_orphan_group(item.child_pid, job_marker(item.job_id, item.attempt), item.worker_id)
        return reclaimed
