"""The navigation tutorials' scenario files, unchanged, on the PyBullet backend (step-based, real engine)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from sim_support import EXAMPLES, PYBULLET_SIM, driven, execute, run, verdicts

NAVIGATION = EXAMPLES / "navigation"


def simulate(scenario: Path, cwd: Path, *extra: str, out: str = "out"):
    done = execute(str(scenario), "--simulation", PYBULLET_SIM, "-o", out, *extra, cwd=cwd)
    return done, verdicts(cwd / out / "test.xml")


def variants(source: Path, tmp_path: Path) -> list[Path]:
    made = run("scenario_variation", str(source), "-o", "in", "--store", f"sqlite:///{tmp_path / 'store.db'}",
               cwd=tmp_path)
    assert made.returncode == 0, made.stdout
    return sorted((tmp_path / "in").glob("*.sce"), key=lambda p: int(re.sub(r"\D", "", p.stem)))


def test_create_navigation_scenario(tmp_path):
    done, result = simulate(NAVIGATION / "example_nav2.osc", tmp_path)
    assert result == {"example_nav2": "passed"}, done.stdout
    assert "navigation up (amcl)" in done.stdout
    (distance, straight), = driven(done.stdout)
    assert abs(distance - straight) < 0.5  # nothing in the way: about the straight line


def test_navigation_with_slam(tmp_path):
    done, result = simulate(NAVIGATION / "example_nav2_slam.osc", tmp_path)
    assert result == {"example_nav2": "passed"}, done.stdout
    assert "navigation up (slam)" in done.stdout


@pytest.mark.slow
def test_navigation_with_obstacle_detours_the_same_way_every_time(tmp_path):
    logs = []
    for i in range(2):
        done, result = simulate(NAVIGATION / "example_simulation.osc", tmp_path, out=f"out{i}")
        assert result == {"example_simulation": "passed"}, done.stdout
        logs.append([line for line in done.stdout.splitlines() if "goal" in line or "spawned" in line])
    assert "within 0.40 m of (1.50, -1.50)" in done.stdout
    assert "a 0.25x0.25x0.25 m box (its SDF box geometry)" in done.stdout
    (distance, straight), = driven(done.stdout)
    assert distance > straight + 0.3  # the robot went around the box
    assert logs[0] == logs[1]  # deterministic: the same spawn, detour and times on every run


@pytest.mark.slow
def test_nav_to_pose_variants_reach_both_goals(tmp_path):
    files = variants(NAVIGATION / "test_nav_to_pose.osc", tmp_path)
    assert [f.name for f in files] == ["test_nav_to_pose0.sce", "test_nav_to_pose1.sce"]
    for i, variant in enumerate(files):
        done, result = simulate(variant, tmp_path, out=f"out{i}")
        (name, verdict), = result.items()            # a variant's testcase is named after the variant
        assert name.startswith(f"{variant.stem}[") and verdict == "passed", done.stdout
    assert "goal accepted: (3.00, 3.00, yaw 0.00)" in done.stdout  # behind the shelf wall


@pytest.mark.slow
def test_fault_injection_variant_runs_and_records(tmp_path):
    files = variants(NAVIGATION / "test_fault_injection.osc", tmp_path)
    assert len(files) == 64
    done, result = simulate(files[0], tmp_path)  # no noise, no drops
    assert list(result.values()) == ["passed"], done.stdout
    assert "set laserscan_modification.gaussian_noise_std_deviation = 0.0" in done.stdout
    assert len(driven(done.stdout)) == 2  # there and back
    bag = tmp_path / "out" / "rosbag2"  # timestamp_suffix: false
    metadata = json.loads((bag / "metadata.json").read_text(encoding="utf-8"))
    assert metadata["not_simulated"] == ["/tf_static"]
    topics = {json.loads(line)["topic"] for line in (bag / "messages.jsonl").read_text(encoding="utf-8").splitlines()}
    assert topics == {"/robot_pose_loc", "/robot_pose_gt", "/cmd_vel", "/amcl_pose", "/odom", "/tf"}


@pytest.mark.slow
def test_strong_scan_noise_makes_navigation_give_up(tmp_path):
    files = variants(NAVIGATION / "test_fault_injection.osc", tmp_path)
    done, result = simulate(files[56], tmp_path)  # noise 0.7 m, no drops
    assert "gaussian_noise_std_deviation = 0.7" in done.stdout
    assert list(result.values()) == ["failure"]
    assert "gave up after 6 recoveries" in done.stdout


def scenario(tmp_path: Path, body: str, imports: str = "import osc.helpers\nimport osc.ros\nimport osc.nav2\n") -> Path:
    path = tmp_path / "s.osc"
    path.write_text(imports + "\nscenario s:\n    timeout(60s)\n    robot: differential_drive_robot\n"
                    "    do serial:\n" + "".join(f"        {line}\n" for line in body.strip().splitlines()),
                    encoding="utf-8")
    return path


def test_no_path_aborts_like_nav2(tmp_path):
    path = scenario(tmp_path, """
robot.init_nav2(pose_3d(position_3d(x: 0.0m, y: 0.0m)))
robot.nav_to_pose(pose_3d(position_3d(x: 20.0m, y: 0.0m)))
""")
    done, result = simulate(path, tmp_path)
    assert result == {"s": "failure"}
    assert "goal aborted: no path to (20.00, 0.00); gave up after 6 recoveries" in done.stdout


def test_parameters_and_ros_only_actions_fail_clearly(tmp_path):
    cases = {
        "set_node_parameter('amcl', 'alpha1', '0.3')":
            "no node 'amcl' in the simulated system (nodes: controller_server, laserscan_modification)",
        "set_node_parameter('laserscan_modification', 'random_drop_percentage', '1.5')":
            "laserscan_modification refused random_drop_percentage = '1.5': must be within [0, 1]",
        "set_node_parameter('laserscan_modification', 'random_drop_percentage', 'lots')":
            "is a float parameter: 'lots' is not one",
        "topic_publish('/cmd_vel', 'geometry_msgs.msg.Twist', '{}')": "needs ROS",
    }
    for call, message in cases.items():
        path = scenario(tmp_path, call)
        done = execute(str(path), "--simulation", PYBULLET_SIM, cwd=tmp_path)
        assert done.returncode == 1 and message in done.stdout, (call, done.stdout)
        assert re.search(r"s\.osc:\d+:\d+: error: action '", done.stdout), done.stdout


def test_gazebo_spawn_delete_exists_and_odometry(tmp_path):
    (tmp_path / "crate.sdf").write_text("<sdf><model name='c'><static>true</static><link name='l'><collision "
                                        "name='c'><geometry><box><size>0.4 0.3 0.2</size></box></geometry>"
                                        "</collision></link></model></sdf>", encoding="utf-8")
    path = scenario(tmp_path, """
wait_for_sim()
robot.init_nav2(pose_3d(position_3d(x: 0.0m, y: 0.0m)))
crate.spawn(pose_3d(position_3d(x: 3.0m, y: 1.0m)), 'my_package://crate.sdf')
ghost.spawn(pose_3d(position_3d(x: -3.0m, y: 1.0m)), 'model://ghost/model.sdf')
actor_exists('crate')
crate.delete('crate')
actor_exists('crate') with:
    failure_is_success()
parallel:
    robot.nav_to_pose(pose_3d(position_3d(x: 1.5m, y: 0.0m)))
    robot.odometry_distance_traveled(1m)
robot.tf_close_to(0.3m, position_3d(x: 1.5m, y: 0.0m), robot_frame_id: 'robot_base_link_gt')
""", imports="import osc.helpers\nimport osc.ros\nimport osc.nav2\nimport osc.gazebo\n")
    text = path.read_text(encoding="utf-8").replace("    robot: differential_drive_robot\n",
                                                    "    robot: differential_drive_robot\n    crate: osc_actor\n"
                                                    "    ghost: osc_actor\n")
    path.write_text(text, encoding="utf-8")
    done, result = simulate(path, tmp_path)
    assert result == {"s": "passed"}, done.stdout
    assert "spawned 'crate' at (3.00, 1.00): model 'my_package://crate.sdf': a 0.4x0.3x0.2 m box" in done.stdout
    assert "model 'model://ghost/model.sdf' not found: a 0.5x0.5x0.5 m box stands in for it" in done.stdout
    assert "deleted 'crate'" in done.stdout


def test_wall_clock_tick_without_a_simulation(tmp_path):
    path = scenario(tmp_path, """
robot.init_nav2(pose_3d(position_3d(x: 0.0m, y: 0.0m)))
robot.nav_to_pose(pose_3d(position_3d(x: 1.0m, y: 0.0m)))
""")
    done = execute(str(path), "-s", "0.05", "-o", "out", cwd=tmp_path)
    assert verdicts(tmp_path / "out" / "test.xml") == {"s": "passed"}, done.stdout
