"""Everyday forms of scenario files written for the reference (issues 10 and 20), through the real CLI."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXE = str(Path(sys.executable).parent / "scenario_execution")


def run(tmp_path: Path, text: str, *args: str, name: str = "s.osc") -> subprocess.CompletedProcess:
    (tmp_path / name).write_text(text)
    return subprocess.run([EXE, name, *args], cwd=tmp_path, capture_output=True, text=True, timeout=60,
                          env=dict(os.environ, NO_COLOR="1"))


def logged(done: subprocess.CompletedProcess) -> list[str]:
    return [line.split("[log] ", 1)[1] for line in (done.stdout + done.stderr).splitlines() if "[log] " in line]


def test_numbers_print_the_way_they_were_written(tmp_path):
    done = run(tmp_path, "import osc.helpers\nscenario s:\n    do serial:\n        log(3s)\n        log(2.0s)\n"
                         "        log(2min)\n        log(200ms)\n        log(10km)\n        log([-3, -0.5])\n")
    assert done.returncode == 0, done.stderr
    assert logged(done) == ["3", "2.0", "120", "0.2", "10000", "[-3, -0.5]"]


def test_list_literals_promote_ints_and_mix_kinds_where_anything_prints(tmp_path):
    done = run(tmp_path, 'import osc.helpers\nscenario s:\n    count: int = 3\n    xs: list of float = [1, 2.5]\n'
                         '    do serial:\n        log([1, 2.5])\n        log([count, "label"])\n        log([250ms, 3km])\n'
                         '        log(xs)\n')
    assert done.returncode == 0, done.stderr
    assert logged(done) == ["[1, 2.5]", "[3, 'label']", "[0.25, 3000]", "[1.0, 2.5]"]


@pytest.mark.parametrize(("member", "message", "column"), [
    ('    xs: list of int = [1, "a"]\n', "list element 1: expected int, got string", 27),
    ("    xs: list of int = [1, 2.5]\n", "list element 1: expected int, got float", 27),
])
def test_typed_lists_still_check_each_element_at_its_place(tmp_path, member, message, column):
    done = run(tmp_path, "import osc.helpers\nscenario s:\n" + member + "    do serial:\n        log(xs)\n", "-n")
    assert done.returncode == 1
    assert done.stderr.startswith(f"s.osc:3:{column}: error: {message}")


def test_process_log_check_finds_a_process_by_its_label_only(tmp_path):
    """Issue 20 item 2: an unlabelled run_process is not found under its action's name."""
    unlabelled = run(tmp_path, 'import osc.helpers\nscenario s:\n    do parallel:\n        run_process("printf READY")\n'
                               '        process_log_check("run_process", ["READY"])\n')
    assert unlabelled.returncode == 1
    assert "no run_process labelled 'run_process'" in unlabelled.stdout + unlabelled.stderr
    labelled = run(tmp_path, 'import osc.helpers\nscenario s:\n    do parallel:\n        srv: run_process("printf READY")\n'
                             '        process_log_check("srv", ["READY"])\n', name="t.osc")
    assert labelled.returncode == 0, labelled.stdout + labelled.stderr


@pytest.mark.parametrize("name", ["kg", "m", "s", "A", "K", "mol", "cd", "rad", "factor"])
def test_asam_keywords_are_not_names(tmp_path, name):
    """Issue 10 item 6: SI base unit names and 'factor' cannot name a parameter or variable."""
    done = run(tmp_path, f"import osc.helpers\nscenario t:\n    {name}: float = 1.0\n    do serial:\n        log('x')\n",
               "-n")
    assert done.returncode == 1
    assert done.stderr.startswith(f"s.osc:3:5: error: '{name}' is a keyword of the language")
    fine = run(tmp_path, f"import osc.helpers\nscenario t:\n    {name}_count: int = 1\n    var {name}3: int = 2\n"
                         f"    do serial:\n        log({name}_count)\n", "-n", name="ok.osc")
    assert fine.returncode == 0, fine.stderr


@pytest.mark.parametrize("name", ["end", "fail", "finish"])
def test_a_built_in_event_cannot_be_declared(tmp_path, name):
    """Issue 10 item 5: events are checked when the file is resolved."""
    done = run(tmp_path, f"import osc.helpers\nscenario t:\n    event {name}\n    do serial:\n        log('x')\n", "-n")
    assert done.returncode == 1
    assert done.stderr.startswith(f"s.osc:3:5: error: '{name}' is a built-in event of every scenario")


def test_emitting_an_undeclared_event_is_an_error_at_its_place(tmp_path):
    done = run(tmp_path, "import osc.helpers\nscenario t:\n    event go\n    do serial:\n        emit og\n", "-n")
    assert done.returncode == 1
    assert done.stderr.startswith("s.osc:5:9: error: unknown event 'og'")


def test_until_event_ends_the_behaviour_when_the_event_comes(tmp_path):
    """Issue 10 item 4: 'until @event' in a with: block."""
    import time

    text = ("import osc.helpers\nscenario s:\n    event go\n    do serial:\n        parallel:\n            serial:\n"
            "                wait elapsed(0.3s)\n                emit go\n            serial:\n"
            "                wait elapsed(100s)\n            with:\n                until @go\n        log(\"after\")\n")
    started = time.monotonic()
    done = run(tmp_path, text)
    assert done.returncode == 0, done.stdout + done.stderr
    assert logged(done) == ["after"] and time.monotonic() - started < 20
    unknown = run(tmp_path, text.replace("until @go", "until @og"), "-n", name="u.osc")
    assert unknown.returncode == 1 and unknown.stderr.startswith("u.osc:12:23: error: unknown event 'og'")


@pytest.mark.parametrize("number", ["2²", "٣", "①"])
def test_digits_that_are_not_ascii_are_a_located_error(tmp_path, number):
    """Found by benchmarks/fuzz_front_end.py: '²' passed str.isdigit() and crashed the lexer."""
    done = run(tmp_path, f"import osc.helpers\nscenario t:\n    do serial:\n        log({number})\n", "-n")
    assert done.returncode == 1 and done.stderr.startswith("s.osc:4:") and "Traceback" not in done.stderr


def test_a_sce_with_a_control_character_is_a_located_error(tmp_path):
    (tmp_path / "v.sce").write_text("# scenario_variation .sce, format 1: x\nformat_version: 1\nsource: \x07\n")
    done = subprocess.run([EXE, "-n", "v.sce"], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 1
    assert done.stderr.startswith("v.sce:3:9: error: not a valid .sce file: character 0x7 is not allowed")


def test_a_signed_literal_after_a_value_is_a_located_syntax_error(tmp_path):
    """Issue 10 item 7: '7 -1' is two adjacent literals; '7 - 1' and '7 - -1' are arithmetic."""
    bad = run(tmp_path, "import osc.helpers\nscenario t:\n    do serial:\n        log(7 -1)\n", "-n")
    assert bad.returncode == 1
    assert bad.stderr.startswith("s.osc:4:15: error: two values without an operator between them")
    good = run(tmp_path, "import osc.helpers\nscenario t:\n    do serial:\n        log(7 - 1)\n        log(7 - -1)\n"
                         "        log([1, -1])\n        log(-2)\n", name="g.osc")
    assert good.returncode == 0, good.stderr
    assert logged(good) == ["6", "8", "[1, -1]", "-2"]


def test_comments_and_white_space_anywhere(tmp_path):
    """Issue 10 item 3."""
    text = ("import osc.helpers   # lib   \n\nscenario s:   \n    do serial:    \n# col0 comment\n"
            "            # deeper comment\n        log(/* a\n           spanning comment */ 1)\n  \n"
            "        # between siblings\n        log(\"x # not a comment\")  # trailing  \n")
    done = run(tmp_path, text)
    assert done.returncode == 0, done.stderr
    assert logged(done) == ["1", "x # not a comment"]


def test_keeps_reach_nested_members_of_an_action_struct_parameter(tmp_path):
    """Issue 20 item 3: with: keep(it.pose.position.z == 0.5m), merged into the given or default value."""
    text = ("import osc.helpers\nimport osc.pybullet\nscenario s:\n    husky: actor_pybullet\n    do serial:\n"
            "        husky.spawn(\"husky/husky.urdf\") with:\n            keep(it.pose.position.z == 0.5m)\n"
            "            keep(it.pose.orientation.yaw == 1.0rad)\n"
            "        husky.spawn(\"husky/husky.urdf\", pose_3d(position: position_3d(x: 2m))) with:\n"
            "            keep(it.pose.position.z == 0.5m)\n")
    done = run(tmp_path, text, "-n", "-l")
    assert done.returncode == 0, done.stderr
    model = done.stdout
    assert "'position': {'x': 0.0, 'y': 0.0, 'z': 0.5}, 'orientation': {'roll': 0.0, 'pitch': 0.0, 'yaw': 1.0}" in model
    assert "'position': {'x': 2, 'y': 0.0, 'z': 0.5}" in model    # 2m keeps its int kind, as the reference prints it
    wrong = run(tmp_path, text.replace("it.pose.position.z", "it.pose.position.q"), "-n", name="w.osc")
    assert wrong.returncode == 1 and "q" in wrong.stderr and wrong.stderr.startswith("w.osc:7:")
