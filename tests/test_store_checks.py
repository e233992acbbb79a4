"""Stores, disks and small refusals (issue 32 item 9), each through the real commands.

A store missing a column, or a foreign database, is refused when it is opened (before any job runs); a
full disk names the file; ``index: -5`` in a ``.sce`` is refused; a sampler over no varied parameter
is an error; the stepped-range message never recommends the strategy that failed.
"""

from __future__ import annotations

import sqlite3

from coverage_support import BIN, run

pytest_plugins = ["batch_stores"]            # the pg_url fixture (a fresh PostgreSQL database)

HELLO = 'import osc.helpers\nscenario s:\n    do serial:\n        log("x")\n'
VARIED = ('import osc.helpers\nscenario v:\n    speed: float = 1.0\n    keep(speed in [1.0, 2.0])\n'
          '    do serial:\n        log(speed)\n')


def _inputs(tmp_path, count: int = 2) -> None:
    (tmp_path / "in").mkdir()
    for index in range(count):
        (tmp_path / "in" / f"s{index}.osc").write_text(HELLO, encoding="utf-8")


def _batch(tmp_path, url: str, output: str, *before: str):
    return run(*before, str(BIN / "scenario_batch_execution"), "-i", "in", "-o", output, "--store", url,
               cwd=tmp_path, check=False)


def test_a_store_missing_a_column_is_refused_before_any_job_runs(tmp_path):
    _inputs(tmp_path)
    url = f"sqlite:///{tmp_path / 'store.db'}"
    assert _batch(tmp_path, url, "first").returncode == 0
    with sqlite3.connect(tmp_path / "store.db") as conn:
        conn.execute("ALTER TABLE jobs DROP COLUMN reason")
    done = _batch(tmp_path, url, "second")
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert "its table jobs lacks the column(s) reason" in done.stderr, done.stderr
    assert not (tmp_path / "second" / "s0").exists()


def test_a_foreign_database_is_refused_and_left_as_it_was(tmp_path):
    _inputs(tmp_path)
    for name, setup in (("other.db", ["CREATE TABLE accounts (id INTEGER)"]),
                        ("meta.db", ["CREATE TABLE store_meta (key VARCHAR(64) PRIMARY KEY, value VARCHAR(255), "
                                     "schema_version INTEGER)",
                                     "INSERT INTO store_meta VALUES ('schema', 'another-tool', 2)"])):
        with sqlite3.connect(tmp_path / name) as conn:
            for statement in setup:
                conn.execute(statement)
        done = _batch(tmp_path, f"sqlite:///{tmp_path / name}", f"out-{name}")
        assert done.returncode == 1 and "is not a scenario store" in done.stderr, done.stderr
        with sqlite3.connect(tmp_path / name) as conn:
            tables = {row[0] for row in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        assert "jobs" not in tables and "batches" not in tables


def test_a_file_size_limit_names_the_store_file(tmp_path):
    _inputs(tmp_path, 30)
    url = f"sqlite:///{tmp_path / 'store.db'}"
    done = _batch(tmp_path, url, "results", "prlimit", "--fsize=153600")
    assert done.returncode == 1
    assert f"cannot write the store {tmp_path / 'store.db'}" in done.stderr, done.stderr
    assert "ulimit -f" in done.stderr and "Traceback" not in done.stderr


def test_a_negative_index_in_a_sce_is_refused(tmp_path):
    (tmp_path / "v.osc").write_text(VARIED, encoding="utf-8")
    made = run(str(BIN / "scenario_variation"), "v.osc", "-o", "out", "--store", f"sqlite:///{tmp_path / 'v.db'}",
               cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    sce = tmp_path / "out" / "v1.sce"
    sce.write_text(sce.read_text(encoding="utf-8").replace("index: 1", "index: -5"), encoding="utf-8")
    done = run(str(BIN / "scenario_execution"), str(sce), "-o", "res", cwd=tmp_path, check=False)
    assert done.returncode == 1 and "'index' must be an integer, 0 or more (got -5)" in done.stderr, done.stderr


def test_a_sampler_over_no_varied_parameter_is_an_error(tmp_path):
    (tmp_path / "s.osc").write_text(HELLO, encoding="utf-8")
    for strategy in ("sobol", "lhs"):
        done = run(str(BIN / "scenario_variation"), "s.osc", "--strategy", strategy, "--samples", "4", "-o", "out",
                   "--store", f"sqlite:///{tmp_path / 'v.db'}", cwd=tmp_path, check=False)
        assert done.returncode == 1 and "varies none; nothing to draw" in done.stderr, done.stderr
        assert not (tmp_path / "out").exists() or not any((tmp_path / "out").glob("*.sce"))


def test_the_stepped_range_message_does_not_recommend_the_strategy_used(tmp_path):
    (tmp_path / "r.osc").write_text(VARIED.replace("[1.0, 2.0]", "[0.0..100.0 step 0.0001]")
                                    .replace("keep(speed in [0.0..100.0 step 0.0001])",
                                             "keep(speed in range(0.0, 100.0, 0.0001))"), encoding="utf-8")
    done = run(str(BIN / "scenario_variation"), "r.osc", "--strategy", "lhs", "--samples", "4", "-o", "out",
               "--store", f"sqlite:///{tmp_path / 'v.db'}", cwd=tmp_path, check=False)
    assert done.returncode == 1 and "this range lists 1,000,001 values" in done.stderr, done.stderr
    assert "write real ends without a step" in done.stderr


def test_a_connection_lost_while_the_schema_is_checked_is_tried_again(pg_url):
    """A worker started while its database ends sessions (a restart, an administrator) waits for it:
    the schema check's transaction, cut off by the server, is run again on a new connection."""
    import psycopg
    from sqlalchemy import event, text

    from store.database import ensure_schema, open_engine
    from store.queue_tables import QUEUE_TABLES

    engine = open_engine(pg_url)
    cut = []

    @event.listens_for(engine, "begin")
    def end_the_first_session(conn):         # the server ends the session under the first transaction
        if not cut:
            pid = conn.exec_driver_sql("SELECT pg_backend_pid()").scalar()
            with psycopg.connect(pg_url.replace("postgresql+psycopg://", "postgresql://"), autocommit=True) as admin:
                cut.append(admin.execute("SELECT pg_terminate_backend(%s)", (pid,)).fetchone()[0])

    try:
        ensure_schema(engine, QUEUE_TABLES)
        with engine.connect() as conn:
            assert conn.execute(text("SELECT count(*) FROM jobs")).scalar() == 0
    finally:
        engine.dispose()
    assert cut == [True]
