"""Managed planner and plant (issue 14, item 6): driven through the lifecycle services over DDS, as Nav2's
lifecycle manager drives its nodes; autostarting by default."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from geometry_msgs.msg import Twist
from rclpy.parameter import Parameter

from fastep_core.geometry import Circle
from fastep_core.planning.navigator import Mode
from fastep_core.world import World
from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from fastep_testing.services import Services
from msg_tools import convert

# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(cls: type, context: Any, **params: Any) -> Any:
    return cls(context=context, parameter_overrides=[Parameter(k, value=v)
                                                     for k, v in {**SYNCHRONOUS, **params}.items()])


def _drive(node: PlannerNode) -> None:
    world = World.from_obstacles([0, 0, 10, 10], [Circle((5.0, 2.0), 0.5)])
    node.inputs.on_obstacles(convert.obstacles_to_marker_array(world.obstacle_list))
    node.inputs.on_map(convert.world_to_occupancy_grid(world, 0.5))
    node.inputs.on_odom(convert.state_to_odometry(np.array([1.0, 1.0]), convert.seconds_to_stamp(0.0)))
    node.on_goal(convert.point_to_pose_stamped((9.0, 9.0)))


def test_nodes_autostart_active_by_default(context: Any) -> None:
    # Main: plain nodes, no lifecycle services at all.
    for cls in (PlannerNode, PlantNode):
        node = make(cls, context)
        services = Services(context, node)
        try:
            assert services.state() == 'active'
            assert node.get_parameter('autostart').value is True
        finally:
            services.close()


def test_a_lifecycle_manager_drives_the_planner(context: Any) -> None:
    node = make(PlannerNode, context, autostart=False)
    services = Services(context, node)
    commands: list[Twist] = []
    services.client.create_subscription(Twist, '/cmd_vel', commands.append, 10)
    try:
        assert services.state() == 'unconfigured'
        assert node.control_timer.is_canceled() and node.reports.status()[1] == 'inactive'
        _drive(node)
        assert services.change_state('configure') and services.state() == 'inactive'
        assert node.control_timer.is_canceled()
        assert services.change_state('activate') and services.state() == 'active'
        assert not node.control_timer.is_canceled()
        assert services.spin_until(lambda: any(c.linear.x != 0.0 for c in commands), 10.0)   # it drives
        assert node.reports.status()[1] == Mode.KINEMATIC.value
        commands.clear()
        assert services.change_state('deactivate') and services.state() == 'inactive'
        assert node.control_timer.is_canceled() and node.reports.status()[1] == 'inactive'
        assert services.spin_until(lambda: bool(commands), 10.0)
        assert commands[-1].linear.x == 0.0 and commands[-1].linear.y == 0.0   # a zero cmd_vel stopped it
        assert services.change_state('cleanup') and services.state() == 'unconfigured'
        assert node.goal is None and node.navigator is not None and node.navigator.mode is Mode.IDLE
        assert services.change_state('shutdown') and services.state() == 'finalized'
    finally:
        services.close()


@pytest.mark.parametrize('cls', [PlannerNode, PlantNode])
def test_a_transition_the_state_does_not_have_is_refused_and_the_node_carries_on(context: Any, cls: type) -> None:
    """activate while unconfigured, configure while active: success false, the state as it was (rclpy raised out of
    the service callback, and the process ended: a plant's robot then stopped for good)."""
    params = {'scenario': 'open_field'} if cls is PlantNode else {}
    node = make(cls, context, autostart=False, **params)
    services = Services(context, node)
    try:
        assert not services.change_state('activate') and services.state() == 'unconfigured'
        assert services.change_state('configure') and services.change_state('activate')
        assert not services.change_state('configure') and services.state() == 'active'
        assert not services.change_state('cleanup') and services.state() == 'active'
        assert services.change_state('deactivate') and services.state() == 'inactive'
    finally:
        services.close()


def test_an_inactive_plant_takes_no_commands(context: Any) -> None:
    node = make(PlantNode, context, start=[1.0, 1.0])
    services = Services(context, node)
    try:
        assert services.change_state('deactivate') and services.state() == 'inactive'
        assert node.timer.is_canceled()
        twist = Twist()
        twist.linear.x = 1.0
        node.on_cmd_vel(twist)
        assert not np.any(node.command)
        assert services.change_state('activate') and not node.timer.is_canceled()
        node.on_cmd_vel(twist)
        assert node.command[0] == 1.0
    finally:
        services.close()
