"""The MuJoCo drop example on the real engine: parameters injected into reset(), a verdict from physics."""

from __future__ import annotations

from sim_support import BALL_SIM, EXAMPLES, execute, logged_numbers, mujoco_drop_env, verdicts

DROP = EXAMPLES / "mujoco" / "drop.osc"


def test_ball_dropped_from_two_metres_lands_in_time(tmp_path):
    env = mujoco_drop_env(tmp_path)
    done = execute(str(DROP), "--simulation", BALL_SIM, "-o", "out", cwd=tmp_path, env=env)
    assert done.returncode == 0, done.stdout
    assert verdicts(tmp_path / "out" / "test.xml") == {"drop": "passed"}
    landed = logged_numbers(done.stdout, "log")
    assert abs(landed[0] - (2 * 2.0 / 9.81) ** 0.5) < 0.01  # free fall: t = sqrt(2 h / g)


def test_a_higher_drop_misses_the_timeout_and_a_throw_lands_farther(tmp_path):
    env = mujoco_drop_env(tmp_path)
    (tmp_path / "high.yaml").write_text("drop:\n  drop_height: 5.0\n", encoding="utf-8")
    done = execute(str(DROP), "--simulation", BALL_SIM, "--scenario-parameter-file", "high.yaml", "-o", "high",
                   cwd=tmp_path, env=env)
    assert done.returncode == 1
    assert verdicts(tmp_path / "high" / "test.xml") == {"drop": "failure"}
    assert "timed out after 1.0s" in (tmp_path / "high" / "test.xml").read_text(encoding="utf-8")

    (tmp_path / "throw.yaml").write_text("drop:\n  throw_speed: 2.0\n", encoding="utf-8")
    runs = [execute(str(DROP), "--simulation", BALL_SIM, "--scenario-parameter-file", "throw.yaml", "-o", f"t{i}",
                    cwd=tmp_path, env=env) for i in range(2)]
    assert all(r.returncode == 0 for r in runs), runs[0].stdout
    assert "landed at 0.640 s, 1.280 m from below the start" in runs[0].stdout
    assert runs[0].stdout == runs[1].stdout  # the same parameters give the same physics


def test_the_action_needs_the_simulation(tmp_path):
    env = mujoco_drop_env(tmp_path)
    done = execute(str(DROP), "-o", "out", cwd=tmp_path, env=env)
    assert done.returncode == 1
    assert "needs the step-based simulation: --simulation examples.mujoco.sim:BallSimulation" in done.stdout
