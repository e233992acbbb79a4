"""Per-job coverage in the store, on SQLite and PostgreSQL: record, replace, read back with the verdicts."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pytest

from store.coverage_records import CoverageRecords, coverage_schemas
from store.database import SCHEMA_VERSION, ensure_schema, open_engine
from store.jobs import BatchOptions, JobResult, JobSpec, WorkerIdentity
from store.queue import QueueStore
from store.states import JobState

pytest_plugins = ["batch_stores"]


def _document(value: float, verdict: str = "passed", samples: list | None = None) -> dict:
    return {"format": "scenario-coverage/run", "format_version": 1,
            "run": {"scenario": "s", "verdict": verdict, "assignment": {"s.x": value}},
            "items": [{"name": "v", "kind": "cover", "path": "s", "type": "float", "range": [0, 10], "every": 5,
                       "samples": samples if samples is not None else [value]},
                      {"name": "t", "kind": "record", "path": "s", "type": "float", "ignored": 1, "samples": [1.0]}]}


def _batch(url: str, names: list[str]):
    queue = QueueStore.open(url)
    batch = queue.create_batch(mode="local", input_dir="/in", output_dir="/out", host="h", command=["x"],
                               options=BatchOptions(), specs=[JobSpec(n, f"/in/{n}.sce", "0") for n in names])
    return queue, batch


def test_record_and_read_back_a_batchs_coverage(store_url):
    queue, batch = _batch(store_url, ["a", "b", "c"])
    worker = WorkerIdentity.current()
    claimed = queue.claim(worker, limit=2, batch_id=batch.id)
    records = CoverageRecords.open(store_url)
    for job, value in zip(claimed, (2.0, 7.0), strict=True):
        queue.finish(job, JobResult(JobState.PASSED, 0, 1.0, 2.0))
        records.record(job.id, job.attempts, _document(value))
    rows = list(records.iter_batch(batch.id, chunk=2))         # chunked reading crosses a chunk border
    assert [(r.name, r.status) for r in rows] == [("a", "passed"), ("b", "passed"), ("c", "queued")]
    assert rows[2].body is None and rows[0].schema_id == rows[1].schema_id     # one declaration set, shared
    assert json.loads(rows[1].body) == [[7.0], [7.0, 1.0], None, [0, 1]]     # values, one, samples, ignored
    assert records.document(claimed[0].id, "scenario-coverage/run", 1) == _document(2.0)
    with records.engine.connect() as conn:
        assert conn.execute(coverage_schemas.select()).all().__len__() == 1
    records.close()
    queue.close()


def test_a_later_attempt_replaces_an_earlier_one_never_the_reverse(store_url):
    queue, batch = _batch(store_url, ["a"])
    job = queue.jobs(batch.id)[0]
    records = CoverageRecords.open(store_url)
    records.record(job.id, 2, _document(3.0, samples=[3.0, 4.0]))
    records.record(job.id, 1, _document(9.0))
    assert records.document(job.id, "f", 1)["items"][0]["samples"] == [3.0, 4.0]
    records.record(job.id, 3, _document(6.0))
    assert records.document(job.id, "f", 1)["run"]["assignment"] == {"s.x": 6.0}
    records.close()
    queue.close()


def test_a_version_1_store_is_upgraded_in_place(tmp_path):
    url = f"sqlite:///{tmp_path / 'old.db'}"
    queue, batch = _batch(url, ["a"])
    queue.close()
    with sqlite3.connect(tmp_path / "old.db") as conn:
        conn.execute("UPDATE store_meta SET schema_version = 1")
        conn.execute("DROP TABLE IF EXISTS job_coverage")
    records = CoverageRecords.open(url)
    records.record(1, 1, _document(1.0))
    records.close()
    with sqlite3.connect(tmp_path / "old.db") as conn:
        assert conn.execute("SELECT schema_version FROM store_meta").fetchone() == (SCHEMA_VERSION,)
    with sqlite3.connect(tmp_path / "old.db") as conn:
        conn.execute("UPDATE store_meta SET schema_version = 99")
    from store.database import StoreError

    with pytest.raises(StoreError, match="schema version 99"):
        ensure_schema(open_engine(url))


def test_reading_opens_only_an_existing_store_and_changes_nothing(store_url):
    """``open_existing`` (the report's way in): no store is no store; an old one is read, not upgraded."""
    from sqlalchemy import inspect, text

    from store.database import StoreMissing, sqlite_file

    with pytest.raises(StoreMissing, match="no store|not a scenario store"):
        CoverageRecords.open_existing(store_url)
    file = sqlite_file(store_url)
    assert file is None or not Path(file).exists()             # the failed open created nothing …
    engine = open_engine(store_url)
    assert inspect(engine).get_table_names() == []            # … in the PostgreSQL database either
    queue, batch = _batch(store_url, ["a", "b"])
    queue.close()
    with engine.begin() as conn:                               # as a version-1 release left it
        conn.execute(text("UPDATE store_meta SET schema_version = 1"))
        conn.execute(text("DROP TABLE IF EXISTS job_coverage"))
        conn.execute(text("DROP TABLE IF EXISTS coverage_schemas"))
    tables = set(inspect(engine).get_table_names())
    records = CoverageRecords.open_existing(store_url)
    rows = list(records.iter_batch(batch.id))
    records.close()
    assert [(r.name, r.status, r.body) for r in rows] == [("a", "queued", None), ("b", "queued", None)]
    engine.dispose()
    assert set(inspect(engine).get_table_names()) == tables
    with engine.connect() as conn:
        assert conn.execute(text("SELECT schema_version FROM store_meta")).scalar() == 1
    engine.dispose()


_COVERAGE_CHILD = r'''
import os, sys
scenario, out = sys.argv[1], sys.argv[2]
os.makedirs(out, exist_ok=True)
with open(os.path.join(out, "test.xml"), "w") as handle:
    handle.write('<testsuite tests="1"><testcase classname="c" name="sc"/></testsuite>')
text = open(scenario).read().strip()
if text:
    with open(os.path.join(out, "coverage.json"), "w") as handle:
        handle.write(text)
'''


def test_the_runner_records_a_jobs_file_and_refuses_a_bad_one(tmp_path):
    """Through the real CLI (launched children): a valid coverage.json is kept in the store with the job, one that
    does not validate is said with its location and left out (the job still passes), a job without one records
    nothing."""
    import subprocess
    import sys

    from batch_fixtures import CLI, cli_env

    child = tmp_path / "child.py"
    child.write_text(_COVERAGE_CHILD)
    inputs = tmp_path / "in"
    inputs.mkdir()
    (inputs / "a.sce").write_text(json.dumps(_document(4.0)))
    (inputs / "b.sce").write_text('{"format": "scenario-coverage/run"}')
    (inputs / "c.sce").write_text("")
    url = f"sqlite:///{tmp_path / 's.db'}"
    done = subprocess.run([CLI, "-i", str(inputs), "-o", str(tmp_path / "out"), "--store", url, "-j", "1", "--",
                           sys.executable, "-S", str(child), "{SCENARIO}", "{OUTPUT_DIR}"],
                          cwd=tmp_path, env=cli_env(tmp_path), capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "warning: b: coverage.json not kept: coverage.json:1:1: error: format_version: must be a whole number\n" \
        in done.stderr
    queue = QueueStore.open(url)
    batch = queue.latest_batch()
    assert batch is not None
    jobs = {job.name: job for job in queue.jobs(batch.id)}
    records = CoverageRecords.open_existing(url)
    assert records.document(jobs["a"].id, "scenario-coverage/run", 1)["items"][0]["samples"] == [4.0]
    assert records.document(jobs["b"].id, "f", 1) is None and records.document(jobs["c"].id, "f", 1) is None
    assert [job.status for job in jobs.values()] == [JobState.PASSED] * 3
    records.close()
    queue.close()
