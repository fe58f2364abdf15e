"""diff_drive on the ROS graph: the plant integrates a differential-drive base, the planner drives it with
(v, omega) in base_link, fastep-launch passes model and start, and a live two-robot run is recorded with REP-105
frames and TF (decoded with rosbags) that fastep-report reads."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rosbags.highlevel import AnyReader

from fastep_core.kinematics.diff_drive import DiffDrive
from fastep_core.scenario import load_scenario
from fastep_ros import launch
from fastep_ros.common import StartupError
from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from fastep_testing.graph import free_domain, isolated_env, stop_process, write
from fastep_testing.published import keep_published
from msg_tools import convert, report

# Two bases swap sides past a circle, each starting turned away from its goal (they turn on the spot first).
TWO_BASES = """\
name: two_bases
workspace: [0, 0, 20, 20]
obstacles:
  - circle: {center: [10, 10], radius: 1.5}
robots:
  - name: d1
    model: diff_drive
    start: [3, 8, 3.141592653589793]
    goal: [17, 12]
    radius: 0.35
  - name: d2
    model: diff_drive
    start: [17, 8, 1.5707963267948966]
    goal: [3, 12]
    radius: 0.35
planner: {max_speed: 1.5}
"""


# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(cls: type, context: Any, namespace: str = '', **params: Any) -> Any:
    return cls(context=context, namespace=namespace,
               parameter_overrides=[Parameter(k, value=v) for k, v in {**SYNCHRONOUS, **params}.items()])


def test_plant_drives_a_diff_drive_base_and_reports_what_it_executed(context: Any) -> None:
    node = make(PlantNode, context, '/d1', model='diff_drive', start=[1.0, 2.0, 0.5], max_speed=1.0,
                max_turn_rate=2.0)
    seen: list[Odometry] = []
    keep_published(node.odom_pub, seen.append)
    try:
        assert isinstance(node.model, DiffDrive) and node.trailer_pub is None
        node.advance(1.0)
        twist = Twist()
        twist.linear.x, twist.angular.z = 5.0, -9.0   # beyond the base's limits: it saturates
        node.command, node.command_time = convert.twist_to_command(twist, 'diff_drive'), 1.0
        node.advance(1.2)
        node.publish()
        expected = np.array([1.0, 2.0, 0.5])
        for _ in range(10):
            expected = DiffDrive(1.0, 2.0).integrate(expected, np.array([5.0, -9.0]), 0.02)
        assert node.state == pytest.approx(expected)
        odom = seen[-1]
        assert (odom.header.frame_id, odom.child_frame_id) == ('d1/odom', 'd1/base_link')
        assert convert.odometry_to_state(odom, 'diff_drive') == pytest.approx(expected)
        tw = odom.twist.twist
        assert (tw.linear.x, tw.linear.y, tw.angular.z) == (1.0, 0.0, -2.0)   # body frame, saturated
    finally:
        node.destroy_node()
    with pytest.raises(StartupError, match='parameter start must have 3 values for diff_drive'):
        make(PlantNode, context, model='diff_drive', start=[1.0, 2.0])


def test_planner_drives_a_diff_drive_base_with_speed_and_turn_rate(context: Any) -> None:
    node = make(PlannerNode, context, '/d1', model='diff_drive', robot_radius=0.35, workspace=[0.0, 0.0, 20.0, 20.0])
    sent: list[Twist] = []
    keep_published(node.cmd_pub, sent.append)
    try:
        assert 'diff_drive' in node.describe_parameter('model').additional_constraints
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        node.inputs.on_odom(convert.state_to_odometry([2.0, 2.0, math.pi], frame_id='d1/odom',
                                                      child_frame_id='d1/base_link'))
        node.on_goal(convert.point_to_pose_stamped((15.0, 2.0)))   # straight behind it: it turns first
        node.on_control()
        assert node.reports.status()[1] == 'kinematic'
        v, omega = node.last_command
        assert abs(omega) > 0.0 and v == pytest.approx(0.0, abs=1e-9)
        assert (sent[-1].linear.x, sent[-1].linear.y, sent[-1].angular.z) == (v, 0.0, omega)
    finally:
        node.destroy_node()


def test_launch_passes_a_diff_drive_base_its_model_start_and_limits() -> None:
    scenario = load_scenario('diff_drive_swap')
    plant = launch.plant_params(scenario.robots[1], True, scenario.planner)
    assert plant['model'] == 'diff_drive' and plant['start'] == pytest.approx([45.0, 45.0, math.pi / 2])
    assert plant['max_speed'] == scenario.planner.max_speed
    assert plant['max_turn_rate'] == scenario.planner.max_turn_rate
    assert launch.planner_params(scenario, 1, 'fastep', 0, True)['model'] == 'diff_drive'


def test_two_diff_drive_bases_through_fastep_launch(tmp_path: Path) -> None:
    """Issue 14's target: a recorded live diff-drive run with two robots, odometry in odom frames, /tf present,
    both at their goals."""
    import subprocess

    scenario = write(tmp_path / 'two_bases.yaml', TWO_BASES)
    out, recorded = tmp_path / 'live.json', tmp_path / 'live.mcap'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    proc = subprocess.Popen([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--rtf', '10', '--json',
                             str(out), '--record', str(recorded)], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        stdout, stderr = proc.communicate(timeout=300)
    finally:
        stop_process(proc)
    assert proc.returncode == 0, stdout + stderr
    assert 'Traceback' not in stderr
    robots = json.loads(out.read_text())['runs'][0]['robots']
    goals = {'d1': (17.0, 12.0), 'd2': (3.0, 12.0)}
    for robot in robots:
        assert robot['model'] == 'diff_drive' and robot['reached'] and not robot['collided'], robot
        assert all(len(row) == 4 for row in robot['trajectory'])   # [t, x, y, theta]
        assert math.dist(robot['trajectory'][-1][1:3], goals[robot['name']]) <= 0.3
    with AnyReader([recorded]) as reader:
        messages: dict[str, list[Any]] = {}
        for c, _, raw in reader.messages():
            messages.setdefault(c.topic, []).append(reader.deserialize(raw, c.msgtype))
    for name in goals:
        odometry = messages[f'/{name}/odom']
        assert {(m.header.frame_id, m.child_frame_id) for m in odometry} == {(f'{name}/odom', f'{name}/base_link')}
        assert all(m.twist.twist.linear.y == 0.0 for m in odometry)   # a base moves along its heading only
        assert max(abs(m.twist.twist.angular.z) for m in odometry) > 0.1   # it turned
        commands = messages[f'/{name}/cmd_vel']
        # TwistStamped: fastep-launch's lock step stamps each command with the tick it was decided for.
        twists = [c.twist for c in commands]
        assert all(c.linear.y == 0.0 for c in twists) and any(c.angular.z != 0.0 for c in twists)
        tf = [t for m in messages['/tf'] for t in m.transforms if t.child_frame_id == f'{name}/base_link']
        assert len(tf) == len(odometry) and {t.header.frame_id for t in tf} == {f'{name}/odom'}
        last = tf[-1].transform.translation
        assert math.dist((last.x, last.y), goals[name]) <= 0.3
    static = {(t.header.frame_id, t.child_frame_id) for m in messages['/tf_static'] for t in m.transforms}
    assert static == {('map', 'd1/odom'), ('map', 'd2/odom')}
    assert report.main([str(recorded), '--out', str(tmp_path / 'report')]) == 0
    summary = json.loads((tmp_path / 'report' / 'report.json').read_text())
    assert {r['name']: r['model'] for r in summary['robots']} == {'d1': 'diff_drive', 'd2': 'diff_drive'}


def test_launch_passes_a_mounted_laser_to_the_plant_and_the_planner(tmp_path: Path) -> None:
    path = write(tmp_path / 'mounted.yaml', TWO_BASES.replace(
        'radius: 0.35', 'radius: 0.35\n    sensor: {range: 6.0, beams: 90, mount: [0.2, 0.0, 0.1]}', 1))
    scenario = load_scenario(str(path))
    index = next(k for k, robot in enumerate(scenario.robots) if robot.sensor is not None)
    plant = launch.plant_params(scenario.robots[index], True, scenario.planner, scenario=str(path), index=index)
    assert plant['sensor'][4:] == pytest.approx([0.2, 0.0, 0.1])
    planner = launch.planner_params(scenario, index, 'fastep_route', 0, True)
    assert planner['laser_mount'] == pytest.approx([0.2, 0.0, 0.1])
    assert planner['scan_mode'] == 'required'   # its scans stopping or unusable hold it, from the start
    assert 'scan_mode' not in launch.planner_params(scenario, 1 - index, 'fastep_route', 0, True)   # no laser


def test_a_plant_with_a_mounted_laser_scans_from_the_mount_in_its_own_frame(context: Any, tmp_path: Path) -> None:
    path = tmp_path / 'mounted.yaml'
    write(path, TWO_BASES)
    node = make(PlantNode, context, '/d1', model='diff_drive', start=[2.0, 2.0, 0.0], scenario=str(path),
                sensor=[6.0, 6.2832, 90.0, 0.0, 0.2, 0.0, 0.0], use_sim_time=False)
    try:
        assert node.scanner is not None and node.scanner.spec.mount == (0.2, 0.0, 0.0)
        assert node.scan_frame_id == 'd1/laser'
    finally:
        node.destroy_node()
