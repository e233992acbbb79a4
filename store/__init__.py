"""The store: one SQLAlchemy database (SQLite by default, PostgreSQL for many hosts). Imports nothing else of ours
but the root of user errors (``coverage_engine.errors.UserError``), from which ``StoreError`` derives.

``database``
    a store URL becomes an engine; the schema version is guarded.
``states``
    the job state machine: states, allowed moves, final states.
``jobs``
    frozen records the queue hands out and takes back (batches, jobs, results, workers).
``queue_tables`` / ``queue_statements`` / ``driver_statements``
    the queue's tables and its statements, each state change one guarded UPDATE.
``queue`` / ``queue_reads``
    the durable queue (enqueue, claim, finish, reclaim) and its read-only questions.
``coverage_records``
    each job's ``coverage.json``, kept with the job so a report needs no shared disk.
``variants`` / ``variant_lookup`` / ``variant_history``
    what ``scenario_variation`` generated, how a scenario file maps to its variant, and what
    ``--only-new`` skips.
"""
