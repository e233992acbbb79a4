"""Batch command-line edges: placeholders substituted once and shell-quoted (issue 21 item 4), empty shards,
misspelt subcommands and --version (issues 22 and 17)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from batch_fixtures import alive, child_command, cli_env, run_cli, start_cli, write_child, write_scenarios

from executor.batch.errors import BadCommand
from executor.batch.inputs import MAX_STORED_TEXT, check_command, job_specs
from executor.batch.launch_template import substitute


def test_job_specs_hash_every_file_whole_and_keep_only_small_texts_of_a_shared_batch(tmp_path):
    import hashlib

    sizes = {"small": 100, "edge": MAX_STORED_TEXT, "over": MAX_STORED_TEXT + 1, "large": 3 * MAX_STORED_TEXT + 5}
    files = []
    for name, size in sizes.items():
        path = tmp_path / f"{name}.sce"
        path.write_bytes(b"a" * (size - 1) + b"\n")
        files.append(path)
    shared = {spec.name: spec for spec in job_specs(files)}
    local = {spec.name: spec for spec in job_specs(files, keep_texts=False)}
    for path in files:
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        assert shared[path.stem].scenario_sha == local[path.stem].scenario_sha == digest
        assert local[path.stem].scenario_text is None
    assert shared["small"].scenario_text == "a" * 99 + "\n" and shared["edge"].scenario_text is not None
    assert shared["over"].scenario_text is None and shared["large"].scenario_text is None


def test_a_value_is_never_searched_for_placeholders_again():
    argv = substitute(["run", "{SCENARIO}", "{OUTPUT_DIR}"], "in{OUTPUT_DIR}/a.osc", "res/a").argv
    assert argv == ("run", "in{OUTPUT_DIR}/a.osc", "res/a")
    assert substitute(["x", "--out={OUTPUT_DIR}"], "{OUTPUT_DIR}.osc", "o").argv == ("x", "--out=o")


def test_values_in_a_shell_script_are_variable_references_and_elsewhere_passed_as_they_are():
    name = "a;touch x;b.osc"
    launch = substitute(["sh", "-c", "run {SCENARIO} > {OUTPUT_DIR}/log"], name, "res/a b")
    assert launch.argv == ("sh", "-c", 'run "${SCENARIO}" > "${OUTPUT_DIR}"/log')
    assert dict(launch.environment) == {"SCENARIO": name, "OUTPUT_DIR": "res/a b"}
    assert substitute(["/bin/bash", "-ec", "run '{SCENARIO}'"], name, "o").argv[2] == "run ''\"${SCENARIO}\"''"
    assert substitute(["sh", "-c", 'run "x{SCENARIO}"'], name, "o").argv[2] == 'run "x${SCENARIO}"'
    assert substitute(["env", "-i", "sh", "-c", "run {SCENARIO}"], name, "o").argv[:4] == (
        "env", "-i", f"SCENARIO={name}", "OUTPUT_DIR=o")
    assert substitute(["sh", "script.sh", "{SCENARIO}"], name, "o").argv == ("sh", "script.sh", name)


def test_a_placeholder_where_no_reference_is_safe_is_refused():
    for command in (["python3", "-c", "print('{SCENARIO}')", "{OUTPUT_DIR}"],
                    ["sh", "-c", "run \\{SCENARIO} {OUTPUT_DIR}"],
                    ["sudo", "sh", "-c", "run {SCENARIO} {OUTPUT_DIR}"],
                    ["ssh", "host", "run", "{SCENARIO}", "{OUTPUT_DIR}"]):
        with pytest.raises(BadCommand, match="file name|backslash|environment"):
            check_command(command, require_executable=False)
    check_command(["sudo", "sh", "-c", 'run "$1" "$2"', "sh", "{SCENARIO}", "{OUTPUT_DIR}"],
                  require_executable=False)


QUOTED_TEMPLATES = {
    "single": ["sh", "-c", "{child} '{{SCENARIO}}' '{{OUTPUT_DIR}}'"],
    "double": ["sh", "-c", '{child} "{{SCENARIO}}" "{{OUTPUT_DIR}}"'],
    "bash-pipefail": ["bash", "-o", "pipefail", "-c", "{child} '{{SCENARIO}}' '{{OUTPUT_DIR}}' | cat"],
    "timeout": ["timeout", "600", "sh", "-c", "{child} '{{SCENARIO}}' '{{OUTPUT_DIR}}'"],
    "env": ["env", "sh", "-c", "{child} '{{SCENARIO}}' '{{OUTPUT_DIR}}'"],
    "env-i": ["env", "-i", "sh", "-c", "{child} {{SCENARIO}} {{OUTPUT_DIR}}"],
    "bare": ["sh", "-c", "{child} {{SCENARIO}} {{OUTPUT_DIR}}"],
}


@pytest.mark.parametrize("form", sorted(QUOTED_TEMPLATES))
def test_file_names_never_run_as_shell_code_whatever_wraps_or_quotes_the_placeholder(tmp_path, form):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"a;touch PWN_SEMI;b": "xml=pass", "c$(touch PWN_DOLLAR)d": "xml=pass"},
                    suffix=".osc")
    program = " ".join(child_command(child)[:3])
    template = [arg.format(child=program) for arg in QUOTED_TEMPLATES[form]]
    done = run_cli(["-i", "in", "-o", "results", "--", *template], tmp_path, cli_env(tmp_path))
    assert done.returncode == 0, done.stdout + done.stderr
    assert sorted(p.name for p in tmp_path.rglob("PWN*")) == []
    assert (tmp_path / "results" / "c$(touch PWN_DOLLAR)d" / "test.xml").is_file()


def test_a_scenario_named_like_shell_code_does_not_run_it(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"a;touch pwned;b": "xml=pass"})
    script = " ".join(child_command(child)[:3]).replace("{SCENARIO}", "") + " {SCENARIO} {OUTPUT_DIR}"
    done = run_cli(["-i", "in", "-o", "results", "--", "sh", "-c", script], tmp_path, cli_env(tmp_path))
    assert done.returncode == 0, done.stdout + done.stderr
    assert not (tmp_path / "pwned").exists()
    assert not (Path.cwd() / "pwned").exists()


def test_a_folder_named_with_a_placeholder_runs_its_own_files(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in{OUTPUT_DIR}", {"one": "xml=pass"})
    done = run_cli(["-i", "in{OUTPUT_DIR}", "-o", "results", "--", *child_command(child)], tmp_path,
                   cli_env(tmp_path))
    assert done.returncode == 0, done.stdout + done.stderr
    assert (tmp_path / "results" / "one" / "test.xml").is_file()


def test_an_empty_shard_exits_5_and_says_so(tmp_path):
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {"only": "xml=pass"})
    codes = {}
    for index in (1, 2, 3):
        done = run_cli(["-i", "in", "-o", f"s{index}", "--shard", f"{index}/3", "--", *child_command(child)],
                       tmp_path, cli_env(tmp_path))
        codes[index] = done.returncode
        if done.returncode == 5:
            assert f"warning: shard {index}/3 holds no scenario file: nothing ran" in done.stderr
    assert sorted(codes.values()) == [0, 5, 5]


def test_a_misspelt_subcommand_is_named_with_the_nearest_one(tmp_path):
    done = run_cli(["wroker", "--store", "sqlite:///x.db"], tmp_path, cli_env(tmp_path))
    assert done.returncode == 2
    assert done.stderr.strip().endswith(
        "error: no such subcommand 'wroker' (subcommands: worker, status, report). Did you mean 'worker'?")
    assert not (tmp_path / "x.db").exists()


def test_every_command_says_its_version(tmp_path):
    import subprocess
    import sys
    from importlib.metadata import version

    for name in ("scenario_execution", "scenario_variation", "scenario_batch_execution", "scenario_coverage",
                 "scenario_search"):
        done = subprocess.run([str(Path(sys.executable).parent / name), "--version"], capture_output=True, text=True)
        assert done.returncode == 0 and done.stdout.strip() == f"{name} {version('scenario-coverage')}"


def test_jobs_auto_counts_only_the_cpus_the_process_may_use(tmp_path):
    """``-j auto`` in a container or under ``taskset`` limited to one CPU runs one job at a time."""
    child = write_child(tmp_path)
    write_scenarios(tmp_path / "in", {name: "xml=pass\nsleep=0.5" for name in ("a", "b", "c", "d")})
    exe = str(Path(sys.executable).parent / "scenario_batch_execution")
    start = time.monotonic()
    done = subprocess.run([exe, "-i", "in", "-o", "results", "-j", "auto", "--", *child_command(child)],
                          cwd=tmp_path, env=cli_env(tmp_path), capture_output=True, text=True, timeout=60,
                          preexec_fn=lambda: os.sched_setaffinity(0, {min(os.sched_getaffinity(0))}))
    took = time.monotonic() - start
    assert done.returncode == 0, done.stdout + done.stderr
    assert took >= 2.0, f"four 0.5 s jobs took {took:.2f} s on one CPU: they ran side by side"


def test_ctrl_c_on_jobs_that_ignore_it_ends_by_their_timeout_and_leaves_no_process(tmp_path):
    """Launched jobs that ignore SIGINT, each with a process of its group beside it: a Ctrl-C gives them
    the --grace of 6 s, but their --timeout of 2 s comes first and ends them (SIGTERM); the verdict is the
    timeout, the run ends then, not after the grace, and nothing of the jobs' groups is left."""
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("a", "b"):
        (folder / f"{name}.sce").write_text("")
    script = ("trap '' INT; (exec sleep 60) & echo $! > \"$2/grandchild\"; echo ready; "
              "while :; do sleep 0.05; done")
    runner = start_cli(["-i", "in", "-o", "res", "-j", "2", "--timeout", "2", "--grace", "6", "--", "sh", "-c",
                        script, "sh", "{SCENARIO}", "{OUTPUT_DIR}"], tmp_path, cli_env(tmp_path))
    deadline = time.monotonic() + 60
    logs = [tmp_path / "res" / name / "log.txt" for name in ("a", "b")]
    while not all(log.exists() and "ready" in log.read_text() for log in logs):
        assert time.monotonic() < deadline and runner.poll() is None
        time.sleep(0.02)
    stopped = time.monotonic()
    runner.send_signal(signal.SIGINT)
    out = runner.communicate(timeout=60)[0]
    assert runner.returncode == 130, out
    assert time.monotonic() - stopped < 6, out       # by the timeout's grace, not the cancel's 6 s
    assert re.findall(r"^\[\d/2\] (\w+) ", out, re.M) == ["timeout", "timeout"], out
    for name in ("a", "b"):
        grandchild = int((tmp_path / "res" / name / "grandchild").read_text())
        assert not alive(grandchild), f"{name}'s grandchild outlived its job"
