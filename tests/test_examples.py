"""Every example under examples/ runs as documented (real command, subprocess)."""

from __future__ import annotations

import os
import time
import xml.etree.ElementTree as ET
from pathlib import Path

from cli_support import example_library_env, run_cli

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def names(path: Path) -> list[str]:
    return [case.get("name") for case in ET.parse(path).getroot().iter("testcase")]


def in_order(text: str, *parts: str) -> bool:
    position = 0
    for part in parts:
        position = text.find(part, position)
        if position < 0:
            return False
    return True


def test_hello_world(tmp_path):
    started = time.monotonic()
    done = run_cli(str(EXAMPLES / "hello_world/hello_world.osc"), "-o", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert time.monotonic() - started >= 3.0
    assert in_order(done.stdout, "Hello World!", "Good Bye!")
    assert names(tmp_path / "out/test.xml") == ["hello_world"]


def test_external_method_from_another_directory(tmp_path):
    done = run_cli(str(EXAMPLES / "external_method/example_external_method.osc"), cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    lines = [line.rstrip() for line in done.stdout.splitlines()]
    assert any(line.endswith(" 24") for line in lines) and any(line.endswith(" 120") for line in lines)


def test_multiple_scenarios(tmp_path):
    done = run_cli(str(EXAMPLES / "multiple_scenarios/two_scenarios.osc"), "-o", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert in_order(done.stdout, "running first", "shared by every scenario", "running second")
    assert names(tmp_path / "out/test.xml") == ["first_scenario", "second_scenario"]
    assert (tmp_path / "out/first_scenario").is_dir() and (tmp_path / "out/second_scenario").is_dir()


def test_parameter_override_and_sweep(tmp_path):
    folder = EXAMPLES / "parameter_override"
    done = run_cli(str(folder / "parameter_override.osc"), "--scenario-parameter-file",
                   str(folder / "override.yaml"), cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert in_order(done.stdout, "my_val", "{'x': 1.0, 'y': 2.0, 'z': 0.0}")
    done = run_cli(str(folder / "parameter_override.osc"), "--scenario-parameter-file",
                   str(folder / "sweep.yaml"), "-o", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert in_order(done.stdout, "slow", "medium", "fast")
    assert names(tmp_path / "out/test.xml") == [f"parameter_override-{i}" for i in range(3)]
    assert (tmp_path / "out/parameter_override-0").is_dir() and (tmp_path / "out/fast_run").is_dir()


#: Loaded into the child through PYTHONPATH: adds up every ``time.sleep`` the run asks for and writes the
#: sum when it exits, so "nothing sleeps" is checked by what the process did, not by a wall-clock bound
#: that a loaded machine could miss.
SLEEP_COUNTER = """
import atexit, os, time
_asked = [0.0]
_sleep = time.sleep
def _counting(seconds):
    _asked[0] += seconds
    _sleep(seconds)
time.sleep = _counting
atexit.register(lambda: open(os.environ["SLEPT_FILE"], "w").write(repr(_asked[0])))
"""


def test_step_based_simulation_runs_faster_than_real_time(tmp_path):
    folder = EXAMPLES / "simulation"
    (tmp_path / "sitecustomize.py").write_text(SLEEP_COUNTER)
    slept = tmp_path / "slept"
    env = {"PYTHONPATH": os.pathsep.join([str(tmp_path), str(folder)]), "SLEPT_FILE": str(slept)}
    done = run_cli("falling_ball.osc", "--simulation", "falling_ball.py:FallingBall", cwd=folder, env=env)
    assert done.returncode == 0, done.stdout
    assert float(slept.read_text()) < 0.01  # 1.5 s of simulated time, no sleeping (the wall clock would ask 1.5 s)
    assert in_order(done.stdout, "SIM reset: height=10.0", "dropping the ball", "1.5 s of simulated time",
                    "SIM shutdown after 1501 steps")


def test_example_library_installed(tmp_path):
    env = example_library_env(tmp_path / "site")
    scenario = EXAMPLES / "example_library/scenarios/example_library.osc"
    done = run_cli(str(scenario), "-o", "out", cwd=tmp_path, env=env)
    assert done.returncode == 0, done.stdout
    assert in_order(done.stdout, "custom_action: foo (1/1)", "custom_action: bar (1/2)", "custom_action: bar (2/2)")
    assert names(tmp_path / "out/test.xml") == ["test_example_library"]
