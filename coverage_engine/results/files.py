"""The names of the files a run leaves in its folder, and a batch beside its merged report: defined here
once, imported by the runtime that writes them, the batch that reads and merges them, and the coverage
model and pytest plugin that read them back."""

from __future__ import annotations

#: A run's JUnit report (and a batch's merged report, in the batch's folder).
RESULT_FILE = "test.xml"

#: A job's log: the child's stdout and stderr, written by the kernel.
LOG_FILE = "log.txt"

#: A run's coverage samples (schema in ``docs/coverage-json.md``).
COVERAGE_FILE = "coverage.json"

#: The file a batch leaves beside its merged ``test.xml``: what the variations of its variants declared,
#: so the results folder is reported right where the ``.sce`` files are not (a CI job with only the results).
DECLARED_FILE = "declared.json"
