"""The batch runner: scenario files become jobs in the store's queue, workers run each as a subprocess.

Modules: ``inputs`` (files, shards, the launch command), ``job_run`` (one attempt in a thread),
``verdict`` (judging an attempt), ``junit_read``/``junit_merge`` (child reports in, the merged report
out), ``worker`` (the claim/run/finish loop, no SQL) and its parts: ``claim_pacing`` (when to claim,
back-off while the store is away), ``hand_over`` (the fork server, jobs held ahead), ``recorder``
(store writes of starts and results, grouped), ``leases`` (heartbeats, sweeps) and ``watchdog``;
``progress`` and ``status`` (output for people), ``orchestration`` (what the command line calls).
Shared with ``scenario_execution``: :mod:`executor.process` (one child in its own process group, its
log, its timeout) and :mod:`executor.hooks` (``--post-run``).
"""
