"""``scenario_search`` through the real command in a pipe: rounds, budget, Ctrl-C and --resume, a launched command.

The scenario is a braking test whose verdict is known by arithmetic (it fails when
speed²/(2·decel) + speed·reaction > gap), so every run's verdict is checked against its values.
"""

from __future__ import annotations

import json
import re
import signal
import subprocess
import time
from pathlib import Path

from batch_fixtures import STARTED, cli_env, start_cli
from search_support import fails, round_runs, search_file, write_brake

from store.queue import QueueStore
from store.states import FINAL, JobState

pytest_plugins = ["batch_stores"]

BIN = Path(__import__("sys").executable).parent
SEARCH = str(BIN / "scenario_search")


def search(*args: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([SEARCH, *args], cwd=cwd, env=cli_env(cwd), capture_output=True, text=True,
                          timeout=timeout)


def _check_verdicts(folder: Path, rounds: int) -> list[tuple[str, str, float, float]]:
    """Every run of every round: its verdict is the arithmetic's; returns them all."""
    everything = []
    for number in range(1, rounds + 1):
        runs = round_runs(folder / f"round{number}" / "results")
        for name, status, speed, gap in runs:
            assert status == ("failed" if fails(speed, gap) else "passed"), (number, name, speed, gap)
        everything += runs
    return everything


def test_a_search_spends_its_budget_in_rounds_and_says_so_per_round(tmp_path):
    write_brake(tmp_path)
    done = search("brake.osc", "--budget", "7", "--round", "3", "-j", "2", "--seed", "11", "-o", "search",
                  cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "search brake.osc: goal boundary, budget 7 run(s), 3 a round, seed 11"
    rounds = [line for line in lines if line.startswith("round ")]
    assert [r.split(":")[0].split(" (")[0] for r in rounds] == ["round 1", "round 2", "round 3"]
    assert "3 of 7 run(s)" in rounds[0] and "6 of 7 run(s)" in rounds[1] and "7 of 7 run(s)" in rounds[2]
    assert any(line.startswith("search done: 7 run(s) in 3 round(s)") for line in lines)
    assert "wrote " not in done.stdout                  # the variation's own lines stay out of the search's
    runs = _check_verdicts(tmp_path / "search", 3)
    assert len(runs) == 7
    assert len({(speed, gap) for _, _, speed, gap in runs}) == 7        # each round draws its own variants
    record = search_file(tmp_path / "search")
    assert record["format"] == "scenario-coverage/search" and record["round"] == 3
    assert [(r["round"], r["runs"]) for r in record["rounds"]] == [(1, 3), (2, 3), (3, 1)]
    assert sum(r["failed"] for r in record["rounds"]) == sum(1 for _, s, _, _ in runs if s != "passed")
    assert record["settings"]["seed"] == 11 and record["settings"]["budget"] == 7
    assert [r["strategy"] for r in record["rounds"]] == ["lhs", "boundary", "boundary"]
    assert "round 2 (boundary)" in rounds[1] and "estimate from 3 earlier run(s): boundary" in rounds[1]
    for number, strategy in ((1, "lhs"), (2, "boundary"), (3, "boundary")):    # each variant says its round
        sce = next((tmp_path / "search" / f"round{number}" / "variants").glob("*.sce")).read_text(encoding="utf-8")
        assert f'# proposal {{"round": {number}, "strategy": "{strategy}"' in sce
    kept = json.loads((tmp_path / "search" / "round3" / "results" / "search.json").read_text(encoding="utf-8"))
    assert kept["round"] == 3 and kept["runs_read"] == 6                   # the estimate went with the results


def test_the_search_ends_with_an_estimate_from_every_round_the_last_included(tmp_path):
    """Each round's estimate is made before it runs; the search's own is made again after its last round:
    it is what scenario_variation --from estimates from every round's results."""
    write_brake(tmp_path)
    done = search("brake.osc", "--budget", "7", "--round", "3", "-j", "2", "--seed", "11", "-o", "search",
                  cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    record = search_file(tmp_path / "search")
    assert record["round"] == 3 and record["runs_read"] == 7                   # round 3's run is counted
    results = [str((tmp_path / "search" / f"round{n}" / "results").resolve()) for n in (1, 2, 3)]
    assert record["from"] == results
    sources = [arg for folder in results for arg in ("--from", folder)]
    check = subprocess.run([str(BIN / "scenario_variation"), "brake.osc", *sources, "--strategy", "boundary",
                            "--samples", "1", "-o", "check"], cwd=tmp_path, env=cli_env(tmp_path),
                           capture_output=True, text=True, timeout=300)
    assert check.returncode == 0, check.stdout + check.stderr
    again = json.loads((tmp_path / "check" / "search.json").read_text(encoding="utf-8"))
    assert again["runs_read"] == 7 and again["estimate"] == record["estimate"]
    said = check.stdout.splitlines()
    estimate = said[said.index("round 4, strategy boundary: 7 earlier run(s) read") + 1:]
    words = done.stdout.splitlines()
    last = words[next(i for i, line in enumerate(words) if line.startswith("search done:")) + 1:]
    assert last == [f"  {line}" for line in estimate[:len(last)]] and last[-1].startswith("  goal ")


def test_a_falsify_search_finds_a_failing_variant_and_the_report_marks_it(tmp_path):
    write_brake(tmp_path)
    done = search("brake.osc", "--goal", "falsify", "--objective", "margin", "--budget", "8", "--round", "4",
                  "-j", "2", "--seed", "2", "-o", "search", cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    record = search_file(tmp_path / "search")
    worst = record["estimate"]["worst"]
    assert worst is not None and worst["failed"] is True
    assert fails(worst["assignment"]["brake.speed"], worst["assignment"]["brake.gap"])     # the arithmetic agrees
    assert re.search(r"^  worst case: margin = -[0-9.]+ \(failed\) at speed=", done.stdout, re.MULTILINE)
    report = subprocess.run([str(BIN / "scenario_coverage"), "json", "search"], cwd=tmp_path, capture_output=True,
                            text=True, timeout=300)
    assert json.loads(report.stdout)["search"]["estimate"]["worst"] == worst


def test_a_search_in_a_folder_that_holds_one_is_refused(tmp_path):
    write_brake(tmp_path)
    assert search("brake.osc", "--budget", "2", "--round", "2", "--seed", "1", "-o", "s", cwd=tmp_path).returncode == 0
    again = search("brake.osc", "--budget", "2", "--round", "2", "-o", "s", cwd=tmp_path)
    assert again.returncode == 1 and "holds a search already" in again.stderr and "--resume" in again.stderr
    assert "Traceback" not in again.stderr
    resumed = search("--resume", "--goal", "falsify", "-o", "s", cwd=tmp_path)
    assert resumed.returncode == 2 and "--goal falsify (the search has boundary)" in resumed.stderr
    other_goal = search("--resume", "--resolution", "0.05", "--pass-rate", "0.5", "-o", "s", cwd=tmp_path)
    assert other_goal.returncode == 2, other_goal.stdout + other_goal.stderr
    assert "--resolution 0.05 (the search has 0.01)" in other_goal.stderr
    assert "--pass-rate 0.5 (the search has None)" in other_goal.stderr


def test_a_scenario_that_does_not_parse_is_a_located_error_and_leaves_no_search(tmp_path):
    (tmp_path / "bad.osc").write_text("scenario x:\n    speed: speed with:\n        keep(it in [5mps..nope])\n",
                                      encoding="utf-8")
    done = search("bad.osc", "-o", "s", cwd=tmp_path)
    assert done.returncode == 1 and "bad.osc:3:27: error:" in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "s").exists()                   # nothing to --resume: run it again once it is fixed


def _store_batches(folder: Path) -> dict[str, list]:
    """The jobs of each round's batch in the store of ``folder``, by round folder name."""
    store = QueueStore.open(f"sqlite:///{folder / '.scenario_store.db'}")
    try:
        found = {}
        for number in (1, 2, 3):
            results = (folder / "search" / f"round{number}" / "results").resolve()
            batch = store.latest_batch(output_dir=str(results))
            if batch is not None:
                found[f"round{number}"] = store.jobs(batch.id)
        return found
    finally:
        store.close()


def _wait_for_round_two_running(tmp_path: Path, process: subprocess.Popen, timeout: float = 120) -> None:
    deadline = time.monotonic() + timeout
    while True:
        assert process.poll() is None, process.stdout.read() if process.stdout else ""
        assert time.monotonic() < deadline, "round 2 never ran a job"
        jobs = _store_batches(tmp_path).get("round2", []) if (tmp_path / ".scenario_store.db").exists() else []
        if any(j.status is JobState.RUNNING for j in jobs) and any(j.status in FINAL for j in jobs):
            return
        time.sleep(0.05)


def test_ctrl_c_mid_round_then_resume_records_every_run_once(tmp_path):
    write_brake(tmp_path, hold="400ms")
    process = subprocess.Popen([SEARCH, "brake.osc", "--budget", "12", "--round", "6", "-j", "2", "--seed", "3",
                                "-o", "search"], cwd=tmp_path, env=cli_env(tmp_path), stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    STARTED.append(process)
    _wait_for_round_two_running(tmp_path, process)
    process.send_signal(signal.SIGINT)
    out, _ = process.communicate(timeout=60)
    assert process.returncode == 130, out
    assert "round 1 (lhs): 6 run(s)" in out and "round 2: interrupted" in out and "--resume" in out
    before = _store_batches(tmp_path)
    finished = {j.name for j in before["round2"] if j.status in FINAL}
    cancelled = {j.name for j in before["round2"] if j.status is JobState.CANCELLED}
    assert finished and cancelled and not any(j.status is JobState.RUNNING for j in before["round2"])
    assert [r["round"] for r in search_file(tmp_path / "search")["rounds"]] == [1]

    resumed = search("--resume", "-j", "2", "-o", "search", cwd=tmp_path)
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert "resuming after round 1" in resumed.stdout and "round 1 (" not in resumed.stdout
    assert "search done: 12 run(s) in 2 round(s)" in resumed.stdout
    after = _store_batches(tmp_path)
    assert set(after) == {"round1", "round2"}
    for jobs in after.values():
        assert len(jobs) == 6 and all(j.status in FINAL for j in jobs)
    assert all(j.attempts == 1 for j in after["round1"])                     # round 1 did not run again
    assert all(j.attempts == 1 for j in after["round2"] if j.name in finished)
    assert all(j.attempts == 2 for j in after["round2"] if j.name in cancelled)
    runs = _check_verdicts(tmp_path / "search", 2)
    assert sorted(name for name, *_ in runs[6:]) == sorted(j.name for j in after["round2"])   # each once
    assert [(r["round"], r["runs"]) for r in search_file(tmp_path / "search")["rounds"]] == [(1, 6), (2, 6)]


def test_each_job_runs_the_launched_command_also_after_resume(tmp_path):
    write_brake(tmp_path)
    first = search("brake.osc", "--budget", "2", "--round", "2", "--seed", "5", "-o", "search", "--",
                   str(BIN / "scenario_execution"), "{SCENARIO}", "-o", "{OUTPUT_DIR}", cwd=tmp_path)
    assert first.returncode == 0 and "search done: 2 run(s) in 1 round(s)" in first.stdout, first.stderr
    done = search("--resume", "--budget", "4", "-o", "search", cwd=tmp_path)   # a larger budget: one more round
    assert done.returncode == 0, done.stdout + done.stderr
    assert "search done: 4 run(s) in 2 round(s)" in done.stdout
    assert "Executing scenario" not in done.stdout        # -j 1: the children's output is not the search's
    runs = _check_verdicts(tmp_path / "search", 2)
    assert len(runs) == 4
    store = QueueStore.open(f"sqlite:///{tmp_path / '.scenario_store.db'}")
    try:
        batch = store.latest_batch(output_dir=str((tmp_path / "search" / "round2" / "results").resolve()))
        assert batch is not None and batch.command[0].endswith("scenario_execution")
    finally:
        store.close()
    log = next((tmp_path / "search" / "round1" / "results").glob("brake0/log.txt")).read_text(encoding="utf-8")
    assert "Executing scenario 'brake'" in log


def test_a_search_queues_its_rounds_in_a_postgresql_store(tmp_path, pg_url):
    write_brake(tmp_path)
    done = search("brake.osc", "--budget", "4", "--round", "2", "-j", "2", "--seed", "9", "--store", pg_url,
                  "-o", "search", cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    assert not (tmp_path / ".scenario_store.db").exists()          # the rounds' queues are in PostgreSQL
    store = QueueStore.open(pg_url)
    try:
        for number in (1, 2):
            batch = store.latest_batch(output_dir=str((tmp_path / "search" / f"round{number}" / "results").resolve()))
            assert batch is not None and len(store.jobs(batch.id)) == 2
    finally:
        store.close()
    assert len(_check_verdicts(tmp_path / "search", 2)) == 4


def test_enqueue_only_leaves_each_round_to_the_workers_and_waits_for_it(tmp_path, pg_url):
    """--enqueue-only: each round's jobs go into the shared PostgreSQL store, a worker (another process; on
    another host it would be the same) runs them, and the search proposes the next round only once the
    round has finished: round 2 is estimated from all of round 1."""
    write_brake(tmp_path)
    host = tmp_path / "worker_host"
    host.mkdir()
    worker = start_cli(["worker", "--store", pg_url, "--wait", "--poll", "0.1", "-j", "2"], host, cli_env(host))
    try:
        done = search("brake.osc", "--budget", "6", "--round", "3", "--seed", "4", "--store", pg_url,
                      "--enqueue-only", "-o", "search", cwd=tmp_path)
    finally:
        worker.send_signal(signal.SIGINT)
        worked, _ = worker.communicate(timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.count("queued in the shared store; waiting for 'scenario_batch_execution worker") == 2
    assert "search done: 6 run(s) in 2 round(s)" in done.stdout
    runs = _check_verdicts(tmp_path / "search", 2)            # the search wrote each round's report
    assert len(runs) == 6
    kept = json.loads((tmp_path / "search" / "round2" / "results" / "search.json").read_text(encoding="utf-8"))
    assert kept["runs_read"] == 3                             # round 2 was proposed from every run of round 1
    store = QueueStore.open(pg_url)
    try:
        for number in (1, 2):
            batch = store.latest_batch(output_dir=str((tmp_path / "search" / f"round{number}" / "results").resolve()))
            assert batch is not None and batch.mode == "shared"
            jobs = store.jobs(batch.id)
            assert len(jobs) == 3 and all(j.status in FINAL and j.worker_pid == worker.pid for j in jobs)
    finally:
        store.close()
    assert sum(1 for line in worked.splitlines() if re.match(r"\[\d+\] (passed|failed) +brake\d", line)) == 6, worked
