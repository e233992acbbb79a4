"""A worker that cannot prepare one claimed job, or loses the store while starting its claims, keeps going."""

from __future__ import annotations

import signal
import time
from pathlib import Path

import pytest
from batch_fixtures import child_command, cli_env, ledger, run_cli, start_cli, write_child, write_scenarios

from store.queue import QueueStore
from store.states import JobState

pytest_plugins = ["batch_stores"]            # the store_url and pg_url fixtures


def _enqueue(tmp_path: Path, store_url: str, specs: dict[str, str], env) -> None:
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", specs)
    result = run_cli(["-i", "in", "-o", "results", "--store", store_url, "--enqueue-only", "--",
                      *child_command(child)], tmp_path, env)
    assert result.returncode == 0, result.stderr


def test_a_job_that_cannot_be_prepared_is_an_error_and_the_others_run(store_url, tmp_path):
    env = cli_env(tmp_path)
    _enqueue(tmp_path, store_url, {"a": "sleep=1", "b": "", "c": ""}, env)
    # b's file is gone from this host, so the worker writes the stored copy into its job folder,
    # where a plain file stands in the way.
    (tmp_path / "in" / "b.sce").unlink()
    (tmp_path / "host").mkdir()
    (tmp_path / "host" / "b").write_text("not a folder")
    worker = start_cli(["worker", "--store", store_url, "-j", "3", "--poll", "0.1", "-o", "host"], tmp_path, env)
    out = worker.communicate(timeout=60)[0]
    assert worker.returncode == 0, out
    assert "Traceback" not in out
    store = QueueStore.open(store_url)
    try:
        jobs = {j.name: j for j in store.jobs(store.latest_batch().id)}
    finally:
        store.close()
    assert jobs["a"].status is JobState.PASSED and jobs["c"].status is JobState.PASSED, out
    assert jobs["b"].status is JobState.ERROR and "cannot prepare the job" in jobs["b"].reason
    assert ledger(tmp_path) == {"a": 1, "c": 1}


@pytest.mark.slow
def test_claimed_jobs_are_given_back_when_the_store_fails_while_starting_them(pg_url, tmp_path):
    import psycopg

    env = cli_env(tmp_path)
    names = ["a", "b", "c"]
    _enqueue(tmp_path, pg_url, {n: "" for n in names}, env)
    database = pg_url.rsplit("/", 1)[1]
    with psycopg.connect(f"postgresql://postgres@127.0.0.1:5432/{database}", autocommit=True) as admin:
        # Reading a whole batch row (what a worker does after claiming) fails like a lost connection until
        # the gate opens; the claim itself, which reads only the batch ids and modes, still works.
        columns = [r[0] for r in admin.execute(
            "SELECT column_name FROM information_schema.columns WHERE table_name = 'batches' "
            "AND column_name <> 'options'").fetchall()]
        admin.execute("CREATE TABLE gate (open boolean)")
        admin.execute("""CREATE FUNCTION gate_open() RETURNS boolean LANGUAGE plpgsql STABLE AS $$
            BEGIN
              IF NOT EXISTS (SELECT 1 FROM gate WHERE open) THEN
                RAISE EXCEPTION 'server closed the connection unexpectedly (test)';
              END IF;
              RETURN true;
            END $$""")
        admin.execute("ALTER TABLE batches RENAME TO batches_real")
        admin.execute(f"CREATE VIEW batches AS SELECT {', '.join(columns)}, "
                      "CASE WHEN gate_open() THEN options END AS options FROM batches_real")
        worker = start_cli(["worker", "--store", pg_url, "-j", "3", "--poll", "0.1", "--lease", "60"],
                           tmp_path, env)
        time.sleep(2.0)                         # several claims fail to start while the gate is shut
        assert worker.poll() is None
        admin.execute("INSERT INTO gate VALUES (true)")
        began = time.monotonic()
        out = worker.communicate(timeout=120)[0]
        assert worker.returncode == 0, out
        assert time.monotonic() - began < 30, "the claimed jobs waited for their lease to expire"
        assert "retrying" in out, out
        lost = admin.execute("SELECT count(*) FROM job_attempts WHERE outcome = 'lost'").fetchone()[0]
        statuses = admin.execute("SELECT status, lost FROM jobs").fetchall()
    assert lost == 0 and statuses == [("passed", 0)] * 3, (statuses, out)
    assert ledger(tmp_path) == {n: 1 for n in names}


def _shut_gate(admin, when: str) -> None:
    """A trigger (``when``: its timing, table and condition) that fails the statement like a lost
    connection until a row ``INSERT INTO gate VALUES (true)`` opens the gate."""
    admin.execute("CREATE TABLE gate (open boolean)")
    admin.execute("""CREATE FUNCTION shut_gate() RETURNS trigger LANGUAGE plpgsql AS $$
        BEGIN
          IF NOT EXISTS (SELECT 1 FROM gate WHERE open) THEN
            RAISE EXCEPTION 'server closed the connection unexpectedly (test)';
          END IF;
          RETURN NEW;
        END $$""")
    admin.execute(f"CREATE TRIGGER shut_gate {when} EXECUTE FUNCTION shut_gate()")


@pytest.mark.slow
def test_results_the_store_refuses_for_a_while_are_kept_and_written_once_it_takes_them(pg_url, tmp_path):
    """Recording a job's end fails like a lost connection until a gate opens: the worker keeps the results
    (none is lost, none written twice) and writes them when the store works again."""
    import psycopg

    env = cli_env(tmp_path)
    names = ["a", "b", "c"]
    _enqueue(tmp_path, pg_url, {n: "" for n in names}, env)
    database = pg_url.rsplit("/", 1)[1]
    with psycopg.connect(f"postgresql://postgres@127.0.0.1:5432/{database}", autocommit=True) as admin:
        _shut_gate(admin, "BEFORE INSERT ON job_attempts FOR EACH ROW")
        worker = start_cli(["worker", "--store", pg_url, "-j", "3", "--poll", "0.1", "--lease", "60"],
                           tmp_path, env)
        deadline = time.monotonic() + 30
        while ledger(tmp_path) != {n: 1 for n in names}:      # every job ran; none of its ends is recorded
            assert time.monotonic() < deadline and worker.poll() is None
            time.sleep(0.05)
        time.sleep(1.0)
        assert admin.execute("SELECT count(*) FROM jobs WHERE status = 'running'").fetchone()[0] == 3
        admin.execute("INSERT INTO gate VALUES (true)")
        out = worker.communicate(timeout=120)[0]
        assert worker.returncode == 0, out
        assert "retrying (results are kept until written)" in out, out
        attempts = admin.execute("SELECT count(*) FROM job_attempts").fetchone()[0]
        statuses = admin.execute("SELECT status FROM jobs").fetchall()
    assert attempts == 3 and statuses == [("passed",)] * 3, (attempts, statuses, out)
    assert ledger(tmp_path) == {n: 1 for n in names}


@pytest.mark.slow
def test_a_stop_gives_back_the_jobs_it_held_once_the_store_takes_them_again(pg_url, tmp_path):
    """Ctrl-C while the store refuses to queue jobs again: the runner keeps the jobs it held for its next
    slots (claimed, never started) and gives them back, uncharged, once the store works again; no job is
    left running in the store and none lost an attempt."""
    import psycopg

    env = cli_env(tmp_path)
    child = write_child(tmp_path)
    names = [f"j{i:02d}" for i in range(30)]
    write_scenarios(tmp_path / "in", {n: "sleep=0.5" for n in names})
    database = pg_url.rsplit("/", 1)[1]
    with psycopg.connect(f"postgresql://postgres@127.0.0.1:5432/{database}", autocommit=True) as admin:
        runner = start_cli(["-i", "in", "-o", "results", "--store", pg_url, "-j", "2", "--",
                            *child_command(child)], tmp_path, env)
        deadline = time.monotonic() + 60
        while sum(ledger(tmp_path).values()) < 2:            # it runs, and holds the next jobs
            assert time.monotonic() < deadline and runner.poll() is None
            time.sleep(0.05)
        _shut_gate(admin, "BEFORE UPDATE ON jobs FOR EACH ROW WHEN (OLD.status = 'running' AND NEW.status = 'queued')")
        held = admin.execute("SELECT count(*) FROM jobs WHERE status = 'running'").fetchone()[0]
        assert held > 2, "the runner held no job beyond its two slots"
        runner.send_signal(signal.SIGINT)
        time.sleep(2.0)                                      # the give-back fails, and is tried again
        assert runner.poll() is None, runner.communicate()[0]
        assert admin.execute("SELECT count(*) FROM jobs WHERE status = 'running'").fetchone()[0] > 0
        admin.execute("INSERT INTO gate VALUES (true)")
        out = runner.communicate(timeout=60)[0]
        assert runner.returncode == 130, out
        assert "retrying" in out and "could not be given back" not in out, out
        statuses = dict(admin.execute("SELECT status, count(*) FROM jobs GROUP BY status").fetchall())
        lost = admin.execute("SELECT count(*) FROM jobs WHERE lost > 0").fetchone()[0]
        charged = admin.execute("SELECT count(*) FROM job_attempts WHERE outcome = 'lost'").fetchone()[0]
    assert "running" not in statuses and statuses.get("queued", 0) >= held - 2, (statuses, out)
    assert lost == 0 and charged == 0, out
    ran = ledger(tmp_path)
    assert all(count == 1 for count in ran.values()), ran
    assert sum(statuses.values()) == len(names)
