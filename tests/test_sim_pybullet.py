"""osc.pybullet on the real engine: the reference's example, both tick modes, determinism, missing extra."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

from sim_support import EXAMPLES, PYBULLET_SIM, execute, logged_numbers, run, verdicts

EXAMPLE = EXAMPLES / "pybullet" / "example_pybullet.osc"


def test_example_pybullet_step_based(tmp_path):
    done = execute(str(EXAMPLE), "--simulation", PYBULLET_SIM, "-o", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert verdicts(tmp_path / "out" / "test.xml") == {"example_pybullet": "passed"}


def test_example_pybullet_wall_clock_tick_steps_one_tick_period_per_tick(tmp_path):
    started = time.monotonic()
    done = execute(str(EXAMPLE), "-s", "0.05", "-o", "out", cwd=tmp_path)
    elapsed = time.monotonic() - started
    assert done.returncode == 0, done.stdout
    assert verdicts(tmp_path / "out" / "test.xml") == {"example_pybullet": "passed"}
    assert elapsed > 2.0  # the physics keeps pace with the wall clock: the drive takes real seconds


def test_tick_period_must_be_a_whole_number_of_physics_steps(tmp_path):
    done = execute(str(EXAMPLE), "-s", "0.03", "-o", "out", cwd=tmp_path)
    assert done.returncode == 1
    assert "example_pybullet.osc:12:13: error: action 'simulation_pybullet.run': the tick period of 0.03 s" in done.stdout
    assert "multiple of 1/240 s" in done.stdout
    assert "Traceback" not in done.stdout


def test_the_same_variant_gives_the_same_outcome(tmp_path):
    made = run("scenario_variation", str(EXAMPLES / "pybullet" / "drive_variation_list.osc"), "-o", "in",
               "--store", f"sqlite:///{tmp_path / 'store.db'}", cwd=tmp_path)
    assert made.returncode == 0, made.stdout
    variant = tmp_path / "in" / "drive_variation_list6.sce"  # 5 rad/s, 1 N m
    outputs = []
    for attempt in range(2):
        done = execute(str(variant), "--simulation", PYBULLET_SIM, "-o", f"out{attempt}", cwd=tmp_path)
        assert done.returncode == 0, done.stdout
        outputs.append([line.split("] ", 2)[-1] for line in done.stdout.splitlines() if "[log]" in line])
    drive_time = logged_numbers("\n".join(f"[log] {line}" for line in outputs[0]), "log")
    assert outputs[0] == outputs[1] and len(outputs[0]) == 2  # time and end position, bit for bit
    assert 2.5 < drive_time[0] < 5.0


def test_unknown_model_is_a_located_error(tmp_path):
    scenario = tmp_path / "s.osc"
    scenario.write_text(EXAMPLE.read_text(encoding="utf-8").replace("husky/husky.urdf", "nope/robot.urdf"),
                        encoding="utf-8")
    done = execute(str(scenario), "--simulation", PYBULLET_SIM, "-o", "out", cwd=tmp_path)
    assert done.returncode == 1
    assert "s.osc:10:9: error: action 'actor_pybullet.spawn': model 'nope/robot.urdf' not found" in done.stdout


def _without_pybullet(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """scenario_execution in a process where ``import pybullet`` fails, as without the extra."""
    code = ("import sys; sys.modules['pybullet'] = None; sys.argv = ['scenario_execution'] + sys.argv[1:]; "
            "from cli.scenario_execution import main; main()")
    return subprocess.run([sys.executable, "-c", code, *args], cwd=cwd, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=60)


def test_without_the_extra_the_actions_name_it(tmp_path):
    done = _without_pybullet(str(EXAMPLE), "-o", "out", cwd=tmp_path)
    assert done.returncode == 1
    assert "the PyBullet physics engine is not installed" in done.stdout
    assert "pip install 'scenario-coverage[pybullet]'" in done.stdout
    assert "Traceback" not in done.stdout
    assert verdicts(tmp_path / "out" / "test.xml") == {"example_pybullet": "failure"}
    # parsing and resolving need no engine
    assert _without_pybullet("-n", str(EXAMPLE), cwd=tmp_path).returncode == 0


def test_without_the_extra_the_simulation_names_it(tmp_path):
    done = _without_pybullet(str(EXAMPLE), "--simulation", PYBULLET_SIM, "-o", "out", cwd=tmp_path)
    assert done.returncode == 1
    assert "pip install 'scenario-coverage[pybullet]'" in done.stdout
    assert "Traceback" not in done.stdout
