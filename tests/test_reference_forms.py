"""The reference's language and libraries as they are today (issue 33, items 2 and 3), through the real CLI.

The reference (cps-test-lab/scenario-execution, the 1.8.0 era) was read from a snapshot while writing
these; the files here are small ones of our own in the same forms. What the reference prints or refuses
is stated beside each case.
"""

from __future__ import annotations

import pytest
from sim_support import PYBULLET_SIM, execute, verdicts

from coverage_engine.parse import syntax
from coverage_engine.parse.parser import parse_file
from coverage_engine.resolve.libraries import find_library

HEADER = "import osc.helpers\n\nscenario test_forms:\n"


def osc(tmp_path, body: str, header: str = HEADER, name: str = "forms.osc"):
    path = tmp_path / name
    path.write_text(header + body, encoding="utf-8")
    return path


def logged(text: str) -> list[str]:
    return [line.split("[log] ", 1)[1] for line in text.splitlines() if "[log] " in line]


@pytest.mark.parametrize("head", [
    "import osc.helpers # the helpers   \n",
    "import osc.helpers\t# tab, then blanks \t \n   \n",
    "import osc.helpers  # comment\n    \n\t\n",
    "import osc.helpers\n# a line of its own   \n   \n",
    "import osc.helpers # comment   \r\n  \r\n",
])
def test_a_comment_after_an_import_with_trailing_blanks(tmp_path, head):
    path = osc(tmp_path, '    do serial:\n        log("ran")\n', header=head + "\nscenario test_forms:\n")
    done = execute(str(path), cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert logged(done.stdout) == ["ran"]


def test_physical_values_print_as_the_reference_prints_them(tmp_path):
    path = osc(tmp_path, """    periods: list of time = [100ms, 2s]
    gap: time = 2s
    do serial:
        log(periods)
        log(2 * 3s)
        log(gap)
        log(3s / 2)
        log(50kph * 1s)
        log(6m / 2s)
        log(10m / 2m)
        log(10mps / 2s)
""")
    done = execute(str(path), cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    # the reference 1.8.0 prints exactly these for the same file
    assert logged(done.stdout) == ["[0.1, 2]", "6", "2", "1.5", "13.8888889", "3.0", "5.0", "5.0"]


def test_unit_arithmetic_gives_the_declared_physical_type(tmp_path):
    path = osc(tmp_path, """    reach: length = 50kph * 2s
    pace: speed = 100m / 20s
    do serial:
        log(reach)
        log(pace)
        wait elapsed(reach / pace)
        log("waited")
""")
    done = execute(str(path), cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert logged(done.stdout) == ["27.7777778", "5.0", "waited"]


@pytest.mark.parametrize(("member", "column", "message"), [
    ("    late: time = 50kph * 2s\n", 18, "member 'late': expected time, got length"),
    ("    odd: float = 1 / 2s\n", 18,
     "operator '/' of int and time gives SI(s: -1), and no physical type with these exponents is declared"),
    ("    odd: float = 2m * 3kg\n", 18, "operator '*' of length and mass gives SI("),
])
def test_unit_arithmetic_errors_are_located(tmp_path, member, column, message):
    path = osc(tmp_path, member + '    do serial:\n        log("x")\n')
    done = execute("-n", str(path), cwd=tmp_path)
    assert done.returncode == 1
    assert f"forms.osc:4:{column}: error: " in done.stdout and message in done.stdout, done.stdout
    assert "Traceback" not in done.stdout


@pytest.mark.parametrize(("body", "line", "column", "what"), [
    ("    t: time = 3\n", 4, 15, "member 't'"),
    ("    t: time = 3s\n    keep(t == 3)\n", 5, 5, "keep of 't'"),
    ("    p: position_3d with:\n        keep(it.x == 1)\n", 5, 9, "keep of 'x'"),
])
def test_a_physical_default_or_keep_needs_a_unit(tmp_path, body, line, column, what):
    path = osc(tmp_path, body + '    do serial:\n        log("x")\n')
    done = execute("-n", str(path), cwd=tmp_path)
    assert done.returncode == 1, done.stdout
    assert f"forms.osc:{line}:{column}: error: {what}: a " in done.stdout and "needs a unit" in done.stdout, done.stdout


def test_struct_arguments_and_parameter_files_keep_the_si_reading(tmp_path):
    path = osc(tmp_path, """    p: position_3d = position_3d(1.0, 2.0, 3.0)
    q: position_3d = position_3d(x: 1, y: 2m)
    t: time = 3s
    do serial:
        log(p)
        log(q)
        log(t)
""")
    (tmp_path / "params.yaml").write_text("test_forms:\n  t: 5\n", encoding="utf-8")
    done = execute(str(path), "--scenario-parameter-file", "params.yaml", cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert logged(done.stdout) == ["{'x': 1.0, 'y': 2.0, 'z': 3.0}", "{'x': 1, 'y': 2, 'z': 0.0}", "5"]


#: Every action of the reference's osc.ros, osc.nav2, osc.gazebo and osc.pybullet today, with its parameters in
#: their order (positional arguments bind by it), as its lib_osc files declare them.
REFERENCE_ACTIONS = {
    "osc.gazebo": {
        "actor_exists": ("entity_name", "world_name"),
        "osc_actor.delete": ("entity_name", "world_name"),
        "osc_actor.relative_spawn": ("frame_id", "parent_frame_id", "distance", "model", "world_name",
                                     "xacro_arguments"),
        "osc_actor.spawn": ("spawn_pose", "model", "world_name", "xacro_arguments"),
        "spawn_multiple": ("entities", "world_name"),
        "wait_for_sim": ("timeout", "world_name"),
    },
    "osc.nav2": {
        "differential_drive_robot.follow_waypoints": ("goal_poses", "loop_count", "namespace_override",
                                                      "action_topic", "success_on_acceptance"),
        "differential_drive_robot.init_nav2": ("initial_pose", "base_frame_id", "use_initial_pose",
                                               "namespace_override", "wait_for_initial_pose", "wait_for_amcl"),
        "differential_drive_robot.nav_through_poses": ("goal_poses", "namespace_override", "action_topic",
                                                       "success_on_acceptance"),
        "differential_drive_robot.nav_to_pose": ("goal_pose", "namespace_override", "action_topic",
                                                 "success_on_acceptance"),
    },
    "osc.pybullet": {
        "simulation_pybullet.initialize": ("world",),
        "simulation_pybullet.run": (),
        "actor_pybullet.spawn": ("model", "pose"),
        "actor_pybullet.set_joint_motor_control": ("target_velocity", "force"),
        "actor_pybullet.distance_traveled": ("distance",),
    },
    "osc.ros": {
        "action_call": ("action_name", "action_type", "data", "success_on_acceptance", "transient_local",
                        "result_variable", "result_member_name"),
        "assert_lifecycle_state": ("node_name", "state_sequence", "allow_initial_skip", "fail_on_unexpected",
                                   "keep_running"),
        "assert_tf_moving": ("frame_id", "parent_frame_id", "timeout", "threshold_translation", "threshold_rotation",
                             "wait_for_first_transform", "tf_topic_namespace", "use_sim_time"),
        "assert_topic_latency": ("topic_name", "latency", "comparison_operator", "rolling_average_count",
                                 "wait_for_first_message", "topic_type"),
        "bag_play": ("source", "topics", "publish_clock", "publish_clock_rate", "start_offset"),
        "bag_record": ("topics", "timestamp_suffix", "hidden_topics", "storage", "use_sim_time"),
        "check_data": ("topic_name", "topic_type", "expected_value", "eval_expected_value", "qos_profile",
                       "member_name", "comparison_operator", "fail_if_no_data", "fail_if_bad_comparison",
                       "wait_for_first_message"),
        "check_data_external": ("topic_name", "topic_type", "qos_profile", "file_path", "function_name",
                                "fail_if_no_data", "fail_if_bad_comparison", "wait_for_first_message"),
        "differential_drive_robot.odometry_distance_traveled": ("distance", "namespace_override"),
        "differential_drive_robot.tf_close_to": ("threshold", "reference_point", "robot_frame_id", "sim",
                                                 "namespace_override", "parent_frame_id"),
        "log_check": ("module_name", "values"),
        "ros_launch": ("package_name", "launch_file", "arguments", "wait_for_shutdown", "shutdown_timeout"),
        "ros_run": ("package_name", "executable_name", "wait_for_shutdown", "shutdown_timeout"),
        "service_call": ("service_name", "service_type", "data", "transient_local", "response_variable",
                         "response_member_name"),
        "set_node_parameter": ("node_name", "parameter_name", "parameter_value"),
        "topic_monitor": ("topic_name", "topic_type", "target_variable", "qos_profile", "member_name"),
        "topic_publish": ("topic_name", "topic_type", "value", "qos_profile"),
        "wait_for_data": ("topic_name", "topic_type", "qos_profile"),
        "wait_for_nodes": ("nodes",),
        "wait_for_service_server": ("service", "node_name"),
        "wait_for_services": ("services",),
        "wait_for_topic_publisher": ("topic", "node_name"),
        "wait_for_topic_subscription": ("topic", "node_name"),
        "wait_for_topics": ("topics",),
    },
}


@pytest.mark.parametrize("library", sorted(REFERENCE_ACTIONS))
def test_every_action_of_the_reference_library_is_declared_with_its_parameters(library):
    unit = parse_file(find_library(library))
    ours = {d.name.dotted: tuple(n for m in d.members if isinstance(m, syntax.ParameterDecl) for n in m.names)
            for d in unit.declarations if isinstance(d, syntax.TypeDecl) and d.kind == "action"}
    for action, parameters in REFERENCE_ACTIONS[library].items():
        assert ours.get(action) == parameters, action


ROS_HEADER = "import osc.helpers\nimport osc.ros\nimport osc.nav2\nimport osc.gazebo\n\nscenario test_forms:\n"

#: The forms of the reference's current examples and library tests that need ROS: each resolves, and fails
#: when it runs with the documented "needs ROS" message (never "unknown action").
ROS_ONLY = [
    "ros_launch('my_bringup', 'sim.launch.py')",
    "ros_launch('my_bringup', 'sim.launch.py', [key_value('use_rviz', 'False')], wait_for_shutdown: false)",
    "ros_run('demo_nodes_py', 'talker', wait_for_shutdown: false)",
    "wait_for_nodes(['/talker'])",
    "wait_for_services(['/add_two_ints'])",
    "wait_for_service_server('/add_two_ints', '/server')",
    "wait_for_topic_publisher('/chatter', '/talker')",
    "wait_for_topic_subscription('/chatter', '/listener')",
    "service_call('/add', 'example_interfaces.srv.AddTwoInts', '{\"a\": 1, \"b\": 2}', response_variable: 'sum')",
    "check_data('/chatter', 'std_msgs.msg.String', 'hello', eval_expected_value: false)",
    "log(ament.get_package_share_directory('my_bringup'))",
]


@pytest.mark.parametrize("call", ROS_ONLY)
def test_ros_only_forms_resolve_and_fail_saying_they_need_ros(tmp_path, call):
    path = osc(tmp_path, f"    do serial:\n        {call}\n", header=ROS_HEADER)
    assert execute("-n", str(path), cwd=tmp_path).returncode == 0
    done = execute(str(path), "-o", "out", cwd=tmp_path)
    assert done.returncode == 1, done.stdout
    assert "needs ROS" in done.stdout and "unknown action" not in done.stdout, done.stdout
    assert "Traceback" not in done.stdout
    assert verdicts(tmp_path / "out/test.xml") == {"test_forms": "failure"}


def test_variables_filled_by_actions_compare_with_any_value(tmp_path):
    path = osc(tmp_path, """    var result: int
    do serial:
        parallel:
            action_call('/fibonacci', 'example_interfaces.action.Fibonacci', '{"order": 2}',
                        result_variable: result, result_member_name: 'sequence')
            serial:
                wait result == [0, 1, 1]
                emit end
""", header=ROS_HEADER)
    done = execute("-n", str(path), cwd=tmp_path)
    assert done.returncode == 0, done.stdout


def test_current_nav2_and_gazebo_forms_run_on_pybullet(tmp_path):
    path = osc(tmp_path, """    timeout(120s)
    robot: differential_drive_robot
    do serial:
        robot.init_nav2(pose_3d(position_3d(x: 0.0m, y: 0.0m)), wait_for_amcl: false)
        spawn_multiple([
            spawn_entity('box_a', pose_3d(position_3d(x: 3.0m, y: 2.0m)), 'model://box_a/model.sdf'),
            spawn_entity('box_b', pose_3d(position_3d(x: -3.0m, y: 2.0m)), 'model://box_b/model.sdf')])
        actor_exists('box_a')
        actor_exists('box_b')
        robot.follow_waypoints([pose_3d(position_3d(x: 1.0m, y: 0.0m)), pose_3d(position_3d(x: 0.5m, y: 0.0m))])
        robot.tf_close_to(0.3m, position_3d(x: 0.5m, y: 0.0m), robot_frame_id: 'robot_base_link_gt')
""", header=ROS_HEADER)
    done = execute(str(path), "-o", "out", "--simulation", PYBULLET_SIM, cwd=tmp_path)
    assert done.returncode == 0, done.stdout
    assert "spawned 'box_a' at (3.00, 2.00)" in done.stdout and "spawned 'box_b' at (-3.00, 2.00)" in done.stdout
    assert "through 2 poses" in done.stdout and "goal reached" in done.stdout
    assert verdicts(tmp_path / "out/test.xml") == {"test_forms": "passed"}
