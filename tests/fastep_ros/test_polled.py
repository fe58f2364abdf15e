"""fastep_ros.polled: a planner takes the other robots' odometry when it uses it, without an executor wake-up per
message (issue 16, item 3: the N^2 fan-in)."""

from __future__ import annotations

import time
from typing import Any

from geometry_msgs.msg import PolygonStamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.parameter import Parameter

from fastep_ros.planner import PlannerNode
from fastep_ros.polled import PolledSubscription
from msg_tools import convert, interface
from msg_tools.footprint import circle_footprint
from msg_tools.interface import RELIABLE, offered_qos


def test_a_planner_takes_only_the_newest_odometry_of_another_robot_when_it_uses_it(context: Any) -> None:
    node = PlannerNode(context=context, parameter_overrides=[Parameter('workspace', value=[0.0, 0.0, 10.0, 10.0])])
    # Another robot as the graph shows it: a node of namespace /r2 announcing its footprint and publishing odometry.
    robot = Node('plant', namespace='/r2', context=context)
    robot.create_publisher(PolygonStamped, interface.FOOTPRINT, offered_qos(interface.FOOTPRINT)).publish(
        circle_footprint(0.5, 'r2/base_link'))
    other = robot.create_publisher(Odometry, '/r2/odom', RELIABLE)
    try:
        end = time.monotonic() + 10.0
        while len(node.robots.subscriptions.get('/r2', [])) < 2 and time.monotonic() < end:
            node.discover()
            time.sleep(0.05)
        sub = node.robots.subscriptions['/r2'][1]
        # Not a subscription of the node's: no executor wakes up for the other robots' 50 Hz odometry ...
        assert isinstance(sub, PolledSubscription) and sub not in list(node.subscriptions)
        assert robot.count_subscribers('/r2/odom') == 1   # ... while on the graph it is a subscription like any
        end = time.monotonic() + 10.0
        while other.get_subscription_count() < 1 and time.monotonic() < end:
            time.sleep(0.05)
        for x in (1.0, 2.0, 3.0):
            other.publish(convert.state_to_odometry([x, 5.0]))
        followed = node.robots.fleet.robots['/r2']
        end = time.monotonic() + 10.0
        while followed.position != (3.0, 5.0) and time.monotonic() < end:
            node.take_others()   # what each control tick (and each wall tick) does
            time.sleep(0.02)
        assert followed.position == (3.0, 5.0)
        assert [o.name for o in node.inputs.other_robots(node.now())] == ['r2']
        node.take_others()
        assert followed.position == (3.0, 5.0)   # nothing new: the last pose stays
    finally:
        robot.destroy_node()
        node.destroy_node()
