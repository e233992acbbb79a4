"""The batch runner: scenario files become jobs in the store's queue, workers run each as a subprocess.

``inputs`` / ``launch_template``
    the scenario files (``.osc``/``.sce``), shards, the launch command and its placeholders (never code).
``orchestration``
    what the command line calls: enqueue, run the workers, write the merged report; ``errors`` its failures.
``worker`` and its parts
    the claim/run/finish loop (no SQL), handing its events to ``claim_pacing`` (when to claim, back-off
    while the store is away), ``hand_over`` (the fork server, jobs held ahead), ``recorder`` (store writes
    of starts and results, grouped), ``leases`` (heartbeats, sweeps) and ``watchdog`` (a runner that dies
    takes its processes with it).
``loop_run`` / ``forked_run`` / ``spawned_run`` / ``inbox``
    one attempt driven by the worker's loop, no thread of its own: a built-in job forked by the fork
    server, or a launched command started with ``posix_spawn`` and watched through its process
    descriptor; the loop's inbox waits on both and on the job threads' events.
``job_run`` / ``job_folders``
    one attempt in a thread (jobs with ``--post-run`` hooks or an echoed output) and the job's own folder
    (with the scenario file the job runs there).
``builtin_runner`` / ``forked_process`` / ``fork_errors`` / ``fork_server`` / ``fork_protocol`` / ``fork_child`` / ``fork_dispatch`` / ``worker_server``
    the built-in runner: jobs forked from a server that has imported the runtime once (the worker's
    handle on each, and what can go wrong with it), what a forked child does to become the job, the
    dispatcher that spreads the forks over several warm copies of the server when a worker has many
    slots, and the server a worker starts (or the command line launches early, before the batch is known).
``verdict``
    judging an attempt: how the child ended and the ``test.xml`` it left become a job state and a reason.
``junit_merge`` / ``batch_outcome`` / ``failure_summary``
    the merged report of the store's jobs (built with :mod:`coverage_engine.results`), one verdict per
    variant, and the end-of-run list.
``repeats`` / ``flaky`` / ``history``
    ``--repeat``, flaky variants, and the batches of one store over time.
``folder_history`` / ``coverage_source``
    the chain of batches of one folder, and its runs as the coverage model's input.
``progress`` / ``status``
    output for people.

Shared with ``scenario_execution``: :mod:`executor.children` (child processes, ``--post-run`` hooks).
"""
