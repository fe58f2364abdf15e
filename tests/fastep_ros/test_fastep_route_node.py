"""The planner node runs FAStep-Route (`-p algorithm:=fastep_route`): built in this process, callbacks called."""

from __future__ import annotations

from typing import Any

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.parameter import Parameter

from fastep_core.geometry import Circle, Segment
from fastep_core.planning.navigators.fastep_route import FAStepRoute
from fastep_ros.planner import PlannerNode
from msg_tools import convert

# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(context: Any, **params: Any) -> PlannerNode:
    return PlannerNode(context=context, parameter_overrides=[Parameter(k, value=v)
                                                          for k, v in {**SYNCHRONOUS, **params}.items()])


def test_planner_node_follows_the_route_and_replans_when_the_map_changes(context: Any) -> None:
    node = make(context, algorithm='fastep_route', workspace=[0.0, 0.0, 20.0, 20.0])
    try:
        descriptor = node.describe_parameter('algorithm')
        assert 'fastep_route (FAStep-Route)' in descriptor.description
        assert 'fastep_route' in descriptor.additional_constraints
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((10.0, 10.0), 2.0)]))
        node.inputs.on_odom(convert.state_to_odometry([2.0, 2.0]))
        node.on_goal(convert.point_to_pose_stamped((18.0, 18.0)))
        node.on_control()
        nav = node.navigator
        assert isinstance(nav, FAStepRoute) and nav.route is not None
        assert node.reports.status()[1] == 'kinematic' and np.any(node.last_command != 0.0)
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((10.0, 10.0), 2.0),
                                                                   Circle((4.0, 6.0), 1.0)]))
        assert node.navigator is nav and nav.world is node.inputs.world   # the same navigator, told the new world
        node.on_control()
        assert [reason for _, reason in nav.replan_log] == ['the world changed']
    finally:
        node.destroy_node()


def test_the_navigator_knows_its_robot_by_the_name_the_other_planners_use(context: Any) -> None:
    """Ties before a one-lane passage go by name (planning/safety/passage.py): the planner names its robot as the
    others' planners name it, its namespace without the slash."""
    node = PlannerNode(context=context, namespace='/r7',
                       parameter_overrides=[Parameter('workspace', value=[0.0, 0.0, 20.0, 20.0])])
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((10.0, 10.0), 2.0)]))
        assert node.navigator is not None and node.navigator.name == 'r7'
    finally:
        node.destroy_node()


def test_planner_node_reports_no_valid_path_for_fastep_route(context: Any) -> None:
    node = make(context, algorithm='fastep_route', workspace=[0.0, 0.0, 10.0, 10.0])
    try:
        box = [Segment((6.0, 6.0), (8.0, 6.0)), Segment((8.0, 6.0), (8.0, 8.0)), Segment((8.0, 8.0), (6.0, 8.0)),
               Segment((6.0, 8.0), (6.0, 6.0))]
        node.inputs.on_obstacles(convert.obstacles_to_marker_array(box))
        node.inputs.on_odom(convert.state_to_odometry([1.0, 1.0]))
        node.on_goal(convert.point_to_pose_stamped((7.0, 7.0)))
        node.on_control()
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.ERROR, 'failed') and reason.startswith('no valid path'), reason
    finally:
        node.destroy_node()


def test_fastep_launch_accepts_fastep_route() -> None:
    from fastep_core.scenario import load_scenario
    from fastep_ros import launch
    args = launch._parser().parse_args(['case_study_2', '--algorithm', 'fastep_route'])
    assert args.algorithm == 'fastep_route'
    params = launch.planner_params(load_scenario('case_study_2'), 1, args.algorithm, 0, True)
    assert 'algorithm:=fastep_route' in launch._command('planner', '/r2', params, verbose=False)
