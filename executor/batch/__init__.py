"""The batch runner: scenario files become jobs in the store's queue, workers run each as a subprocess.

Modules: ``inputs`` (files, shards, the launch command), ``process`` (one child in its own process
group, its log, its timeout), ``verdict`` (judging an attempt), ``junit_merge`` (the merged report),
``hooks`` (``--post-run``), ``worker`` (the claim/run/finish loop, no SQL), ``progress`` (output for
people), ``runner`` (what the command line calls).
"""
