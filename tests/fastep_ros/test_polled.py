"""fastep_ros.polled: a planner takes the other robots' odometry when it uses it, without an executor wake-up per
message (issue 16, item 3: the N^2 fan-in)."""

from __future__ import annotations

import time
from typing import Any

from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter

from fastep_ros.planner import PlannerNode
from fastep_ros.polled import PolledSubscription
from msg_tools import convert
from msg_tools.interface import RELIABLE


def test_a_planner_takes_only_the_newest_odometry_of_another_robot_when_it_uses_it(context: Any) -> None:
    node = PlannerNode(context=context, parameter_overrides=[Parameter('workspace', value=[0.0, 0.0, 10.0, 10.0])])
    other = node.create_publisher(Odometry, '/r2/odom', RELIABLE)   # another robot's plant, as seen on the graph
    try:
        end = time.monotonic() + 10.0
        while '/r2/odom' not in node.other_subs and time.monotonic() < end:
            node.discover()
            time.sleep(0.05)
        sub = node.other_subs['/r2/odom']
        # Not a subscription of the node's: no executor wakes up for the other robots' 50 Hz odometry ...
        assert isinstance(sub, PolledSubscription) and sub not in list(node.subscriptions)
        assert node.count_subscribers('/r2/odom') == 1   # ... while on the graph it is a subscription like any
        end = time.monotonic() + 10.0
        while other.get_subscription_count() < 1 and time.monotonic() < end:
            time.sleep(0.05)
        for x in (1.0, 2.0, 3.0):
            other.publish(convert.state_to_odometry([x, 5.0]))
        end = time.monotonic() + 10.0
        while node.others['/r2/odom'].position != (3.0, 5.0) and time.monotonic() < end:
            node.take_others()   # what each control tick (and each wall tick) does
            time.sleep(0.02)
        assert node.others['/r2/odom'].position == (3.0, 5.0)
        assert [o.name for o in node.other_robots(node.now())] == ['r2']
        node.take_others()
        assert node.others['/r2/odom'].position == (3.0, 5.0)   # nothing new: the last pose stays
    finally:
        node.destroy_node()
