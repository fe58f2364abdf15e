"""The plant node with `dynamics`: a physics base whose odometry twist lags the command and whose pose drifts
on slip, the true pose on ground_truth_topic, its parameter's errors. Built in this process (own context,
isolated domain: tests/fastep_ros/conftest.py), its callbacks called directly."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest
import yaml
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter

from fastep_ros.common import StartupError
from fastep_ros.plant import PlantNode
from fastep_testing.published import keep_published
from msg_tools import convert


def make(context: Any, **params: Any) -> PlantNode:
    return PlantNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])


def test_odometry_twist_lags_the_command(context: Any) -> None:
    node = make(context, model='diff_drive', start=[1.0, 2.0, 0.0], rate_hz=50.0, dynamics='heavy',
                ground_truth_topic='ground_truth')
    odometry: list[Odometry] = []
    truth: list[PoseWithCovarianceStamped] = []
    keep_published(node.odom_pub, odometry.append)
    assert node.truth_pub is not None
    keep_published(node.truth_pub, truth.append)
    try:
        assert node.physics is not None and node.physics.dynamics.preset == 'heavy'
        node.advance(10.0)
        speeds = []
        for k in range(1, 76):   # 1.5 s of a fresh 1 m/s command every step (50 Hz)
            t = 10.0 + 0.02 * k
            node.command, node.command_time = np.array([1.0, 0.0]), t - 0.02
            node.advance(t)
            node.publish()
            speeds.append(odometry[-1].twist.twist.linear.x)
        # heavy accelerates at ~0.8 m/s^2: the measured twist lags the command (kinematic: 1.0 at once)
        assert 0.04 < speeds[4] < 0.12   # 0.1 s in: 0.08 at 0.8 m/s^2
        assert 0.7 < speeds[49] < 0.9
        assert speeds[-1] == pytest.approx(1.0, abs=0.02)
        assert max(speeds) < 1.05
        # ground truth: the true pose in map, stamped as the odometry
        last = truth[-1]
        assert last.header.frame_id == 'map'
        assert convert.stamp_to_seconds(last.header.stamp) == pytest.approx(11.5)
        assert convert.stamp_to_seconds(odometry[-1].header.stamp) == pytest.approx(11.5)
        assert (last.pose.pose.position.x, last.pose.pose.position.y) == pytest.approx(
            (float(node.state[0]), float(node.state[1])))
        assert node.state[0] - 1.0 == pytest.approx(0.5 * 0.8 * 1.25 ** 2 + 0.25, abs=0.1)  # ramp, then cruise
        # The command times out after cmd_timeout: the base ramps to a stop
        node.advance(13.5)
        node.publish()
        assert abs(odometry[-1].twist.twist.linear.x) < 0.01
    finally:
        node.destroy_node()


def test_slippery_odometry_drifts_from_the_truth(context: Any) -> None:
    node = make(context, model='diff_drive', start=[0.0, 0.0, 0.0], rate_hz=50.0,
                dynamics='{preset: slippery, encoder_noise: 0.0}', ground_truth_topic='truth')
    odometry: list[Odometry] = []
    keep_published(node.odom_pub, odometry.append)
    try:
        node.advance(1.0)
        for k in range(1, 201):
            t = 1.0 + 0.02 * k
            node.command, node.command_time = np.array([1.2, 0.0 if k < 100 else 1.5]), t - 0.02
            node.advance(t)
        node.publish()
        pose = odometry[-1].pose.pose.position
        assert np.hypot(pose.x - node.state[0], pose.y - node.state[1]) > 0.1
    finally:
        node.destroy_node()


@pytest.mark.parametrize(('params', 'message'), [
    ({'model': 'point_mass', 'start': [0.0, 0.0], 'dynamics': 'heavy'},
     'parameter dynamics is only for model diff_drive, got point_mass'),
    ({'model': 'diff_drive', 'start': [0.0, 0.0, 0.0], 'dynamics': 'fast'},
     'parameter dynamics preset must be one of nominal, heavy, limited_controller, slippery'),
    ({'model': 'diff_drive', 'start': [0.0, 0.0, 0.0], 'dynamics': '{mass: -1}'},
     'parameter dynamics mass must be > 0, got -1'),
])
def test_bad_dynamics_is_one_line(context: Any, params: dict[str, Any], message: str) -> None:
    with pytest.raises(StartupError, match=message.replace('(', r'\(')):
        make(context, **params)


def test_kinematic_by_default(context: Any) -> None:
    node = make(context, model='diff_drive', start=[0.0, 0.0, 0.0], ground_truth_topic='truth')
    try:
        assert node.physics is None and node.truth_pub is None
    finally:
        node.destroy_node()


def test_launch_gives_a_physics_robot_its_dynamics_and_the_ground_truth_as_localization(context: Any) -> None:
    """fastep-launch's parameters: the plant's `dynamics` as the command line carries it (read back by the node to
    the same base), ground_truth_topic, and the planner's localization_topic on it; a kinematic robot has none."""
    from fastep_core.scenario import parse_scenario
    from fastep_ros import launch
    from fastep_ros.processes import ros_value

    robot = {'name': 'd', 'model': 'diff_drive', 'start': [2, 10, 0], 'goal': [18, 12], 'radius': 0.35}
    scenario = parse_scenario({'workspace': [0, 0, 20, 20], 'robots': [
        {**robot, 'dynamics': {'preset': 'heavy', 'mass': 45}},
        {**robot, 'name': 'k', 'start': [2, 5, 0], 'goal': [18, 5]}]})
    plant = launch.plant_params(scenario.robots[0], True, scenario.planner, seed=4, index=0)
    assert plant['ground_truth_topic'] == launch.GROUND_TRUTH_TOPIC and plant['seed'] == 4
    planner = launch.planner_params(scenario, 0, 'fastep_route', 4, True)
    assert planner['localization_topic'] == launch.GROUND_TRUTH_TOPIC
    as_ros_reads_it = yaml.safe_load(ros_value(plant['dynamics']))   # `-p dynamics:=VALUE` is YAML
    node = make(context, model='diff_drive', start=[2.0, 10.0, 0.0], dynamics=as_ros_reads_it)
    try:
        assert node.physics is not None
        expected = scenario.robots[0].dynamics
        assert expected is not None
        assert node.physics.dynamics == replace(expected, cmd_timeout=node.cmd_timeout)
    finally:
        node.destroy_node()
    kinematic = launch.plant_params(scenario.robots[1], True, scenario.planner)
    assert 'dynamics' not in kinematic and 'ground_truth_topic' not in kinematic
    assert 'localization_topic' not in launch.planner_params(scenario, 1, 'fastep_route', 4, True)
