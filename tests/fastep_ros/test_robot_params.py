"""The planner parameters that describe the robot as it is: its outline (`footprint`, Nav2's form), and how far its
pose may be off (`localization_tolerance`, `odometry_drift`, a localization pose's covariance)."""

from __future__ import annotations

import math
from typing import Any

import pytest
from geometry_msgs.msg import PolygonStamped
from rclpy.executors import SingleThreadedExecutor

from fastep_core.scenario import parse_scenario
from fastep_core.world import World
from fastep_ros.common import StartupError
from fastep_ros.launch import planner_params
from fastep_ros.planner import PlannerNode
from msg_tools import convert, interface

JACKAL = '[[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]]'


def make(context: Any, *args: str) -> PlannerNode:
    return PlannerNode(context=context, namespace='/r1',
                       cli_args=['--ros-args', '-p', 'model:=diff_drive', '-p', 'planning_thread:=false', *args])


def announced(context: Any, node: PlannerNode) -> PolygonStamped:
    """The footprint the node published (latched: a late subscriber gets it)."""
    heard: list[PolygonStamped] = []
    listener = node.create_subscription(PolygonStamped, '/r1/footprint', heard.append,
                                        interface.offered_qos(interface.FOOTPRINT))
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        for _ in range(200):
            if heard:
                break
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.remove_node(node)
        node.destroy_subscription(listener)
    assert heard, 'no footprint announced'
    return heard[-1]


def test_a_footprint_in_nav2s_form_is_the_outline_the_robot_announces(context: Any) -> None:
    node = make(context, '-p', f'footprint:="{JACKAL}"', '-p', 'robot_radius:=0.22', '-p', 'obstacle_source:=map')
    try:
        assert node.footprint is not None and node.footprint.to_list()[0] == [0.254, 0.215]
        assert node.radius == pytest.approx(math.hypot(0.254, 0.215))   # robot_radius gives way to the outline
        node.inputs.on_map(convert.world_to_occupancy_grid(World.from_obstacles([0, 0, 10, 10], []), 0.5))
        assert node.navigator is not None and node.navigator.footprint == node.footprint   # guarded by the outline
        points = [(round(p.x, 3), round(p.y, 3)) for p in announced(context, node).polygon.points]
        assert sorted(points) == sorted([(0.254, 0.215), (-0.254, 0.215), (-0.254, -0.215), (0.254, -0.215)])
    finally:
        node.destroy_node()


@pytest.mark.parametrize('value', ['""', '"[]"'])
def test_an_empty_footprint_is_the_circle_of_robot_radius(context: Any, value: str) -> None:
    node = make(context, '-p', f'footprint:={value}', '-p', 'robot_radius:=0.3')
    try:
        assert node.footprint is None and node.radius == 0.3
        assert len(announced(context, node).polygon.points) == 16   # Nav2's circle of 16 points
    finally:
        node.destroy_node()


@pytest.mark.parametrize(('args', 'words'), [
    (('-p', 'footprint:="[[0.2, 0.2], [-0.2, 0.2]]"'), 'parameter footprint'),
    (('-p', 'footprint:="[[1, 1], [2, 1], [2, 2], [1, 2]]"'), 'parameter footprint'),   # base_link outside it
    (('-p', 'footprint:="[[0.2, 0.2], [nan, 0.2], [0.0, -0.2]]"'), 'parameter footprint'),
    (('-p', f'footprint:="{JACKAL}"', '-p', 'model:=point_mass'), 'diff_drive'),
])
def test_a_footprint_that_is_no_outline_is_refused_in_one_line(context: Any, args: tuple[str, ...],
                                                                words: str) -> None:
    with pytest.raises(StartupError) as error:
        make(context, *args)
    assert words in str(error.value) and '\n' not in str(error.value)


def test_fastep_launch_hands_a_scenario_footprint_to_its_planner(context: Any) -> None:
    scenario = parse_scenario({'workspace': [0, 0, 10, 10], 'robots': [
        {'name': 'r1', 'model': 'diff_drive', 'start': [2, 5, 0.0], 'goal': [8, 5],
         'footprint': [[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]]}]})
    value = planner_params(scenario, 0, 'fastep_route', 1, sim_time=False)['footprint']
    node = make(context, '-p', f'footprint:={value}')   # as fastep-launch's command line passes it
    try:
        assert node.footprint == scenario.robots[0].footprint
    finally:
        node.destroy_node()


def test_the_pose_tolerances_reach_perception_and_a_localization_pose_bounds_them(context: Any) -> None:
    """localization_tolerance and odometry_drift as perception takes them; amcl_pose's covariance adds its bound
    and starts the drift again."""
    from geometry_msgs.msg import PoseWithCovarianceStamped
    node = make(context, '-p', 'localization_tolerance:=[0.05, 0.01]', '-p', 'odometry_drift:=[0.02, 0.0]',
                '-p', 'localization_topic:=amcl_pose')
    try:
        perception = node.inputs.scan_perception
        assert (perception.uncertainty.translation, perception.uncertainty.yaw) == (0.05, 0.01)
        perception.driven = 10.0
        assert perception.pose_uncertainty().translation == pytest.approx(0.05 + 0.2)
        msg = PoseWithCovarianceStamped()
        msg.header.frame_id = 'map'
        msg.pose.pose.orientation.w = 1.0
        msg.pose.covariance[0] = msg.pose.covariance[7] = 0.01 ** 2   # 1 cm in x and y
        node.inputs.on_localization(msg)
        assert perception.driven == 0.0
        assert perception.pose_uncertainty().translation == pytest.approx(0.05 + 3 * 0.01)   # 3 sigmas
    finally:
        node.destroy_node()


def test_a_pose_tolerance_that_is_no_pair_of_numbers_is_refused(context: Any) -> None:
    with pytest.raises(StartupError, match='parameter odometry_drift must be two finite numbers >= 0'):
        make(context, '-p', 'odometry_drift:=[0.01, -1.0]')


def test_fastep_launch_judges_a_footprint_robot_by_its_outline_at_each_heading() -> None:
    """A 0.7 x 0.5 m box driving past a wall 0.3 m to its side: clear by its outline (0.05 m), where its
    circumscribed circle (0.43 m) would have been 0.13 m inside the wall; turned across, the box itself touches."""
    from fastep_ros.launch_report import _min_clearance
    from fastep_ros.monitor import RobotLive
    box = [[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]
    scenario = parse_scenario({'workspace': [0, 0, 10, 10],
                               'obstacles': [{'segment': {'start': [0.0, 5.3], 'end': [10.0, 5.3]}}],
                               'robots': [{'name': 'r1', 'model': 'diff_drive', 'start': [1, 5, 0.0],
                                           'goal': [9, 5, 0.0], 'footprint': box}]})
    along = RobotLive(scenario.robots[0], rows=[[0.1 * k, 1.0 + 0.5 * k, 5.0, 0.0] for k in range(10)])
    assert _min_clearance(scenario, {'r1': along})['r1'] == pytest.approx(0.05)
    across = RobotLive(scenario.robots[0], rows=[[0.0, 1.0, 5.0, 0.0], [0.1, 1.0, 5.0, math.pi / 2]])
    assert _min_clearance(scenario, {'r1': across})['r1'] == pytest.approx(-0.05)
