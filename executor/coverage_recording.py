"""What the batch runner calls when it records a job's result: keep the job's ``coverage.json`` in the store.

    records = CoverageRecords.attach(store.engine)          # once per runner or worker
    ...
    problem = record_job_coverage(records, job.id, job.attempts, job_output_dir)
    if problem: log it (the job's verdict stands; its items are left out of reports)

A job that wrote no ``coverage.json`` records nothing and still counts for input coverage. A file
that does not validate is not stored; the located error comes back as text for the job's log.
"""

from __future__ import annotations

import os

from coverage_engine.coverage.errors import RunFileError
from coverage_engine.coverage.run_file import RUN_FILE, read_run_coverage, run_coverage_dict
from store.coverage_records import CoverageRecords


def record_job_coverage(records: CoverageRecords, job_id: int, attempt: int, folder: str | os.PathLike[str]) -> str | None:
    """Read ``folder/coverage.json`` (if there is one) and record it for the job's attempt; the error, if any."""
    path = os.path.join(folder, RUN_FILE)
    if not os.path.isfile(path) or os.path.islink(path):
        return None
    try:
        run = read_run_coverage(path)
    except RunFileError as exc:
        return exc.render()
    records.record(job_id, attempt, run_coverage_dict(run))
    return None
