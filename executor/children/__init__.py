"""The child processes we start, shared by both commands that start them.

``process``
    one child in its own process group: its log file, its timeout, its cancellation, the orphans it
    leaves (batch jobs, launched or forked, and hooks use it).
``hooks``
    ``--post-run CMD`` of ``scenario_execution`` (once, on the output folder) and of
    ``scenario_batch_execution`` (after each job, on the job's folder), each a :mod:`process` child.
"""
