"""/diagnostics as Nav2 nodes publish it (issue 14, item 6): received over DDS from nodes built in this process."""

from __future__ import annotations

from typing import Any

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Twist
from rclpy.parameter import Parameter

from fastep_ros.diagnostics import DIAGNOSTICS
from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from fastep_testing.services import Services
from msg_tools import convert


def make(cls: type, context: Any, namespace: str = '', **params: Any) -> Any:
    return cls(context=context, namespace=namespace,
               parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])


def _listen(services: Services) -> dict[str, DiagnosticStatus]:
    """Every status heard on /diagnostics by name, the latest of each."""
    heard: dict[str, DiagnosticStatus] = {}

    def take(msg: DiagnosticArray) -> None:
        for status in msg.status:
            heard[status.name] = status
    services.client.create_subscription(DiagnosticArray, DIAGNOSTICS, take, 10)
    return heard


def test_planner_publishes_diagnostics_with_stale_odometry(context: Any) -> None:
    # Main: only <ns>/status; nothing on /diagnostics, and no STALE anywhere.
    node = make(PlannerNode, context, namespace='r1', odom_timeout=0.3)
    services = Services(context, node)
    try:
        heard = _listen(services)
        node.inputs.on_odom(convert.state_to_odometry(np.array([1.0, 1.0]), convert.seconds_to_stamp(0.0)))
        names = {'r1/planner: navigation', 'r1/planner: odometry', 'r1/planner: clock'}
        assert services.spin_until(lambda: names <= set(heard), 10.0), heard
        assert all(heard[n].hardware_id == 'r1' for n in names)
        assert heard['r1/planner: navigation'].level == DiagnosticStatus.WARN   # waiting for the world
        assert heard['r1/planner: clock'].level == DiagnosticStatus.OK and heard['r1/planner: clock'].message == \
            'wall time'
        # No odometry for longer than odom_timeout: STALE.
        assert services.spin_until(lambda: heard['r1/planner: odometry'].level == DiagnosticStatus.STALE, 10.0)
        values = {kv.key: kv.value for kv in heard['r1/planner: odometry'].values}
        assert 'odom_timeout 0.3 s' in values['reason'] and values['topic'] == '/r1/odom'
        assert services.set(odom_timeout=30.0)[0].successful
        node.inputs.on_odom(convert.state_to_odometry(np.array([1.0, 1.0]), convert.seconds_to_stamp(0.0)))
        assert services.spin_until(lambda: heard['r1/planner: odometry'].level == DiagnosticStatus.OK, 10.0)
    finally:
        services.close()


def test_plant_publishes_diagnostics_with_a_stale_command(context: Any) -> None:
    node = make(PlantNode, context, cmd_timeout=0.2)
    services = Services(context, node)
    try:
        heard = _listen(services)
        names = {'plant: odometry', 'plant: cmd_vel', 'plant: clock'}
        assert services.spin_until(lambda: names <= set(heard), 10.0), heard
        assert heard['plant: odometry'].hardware_id == 'plant'
        twist = Twist()
        twist.linear.x = 0.5
        node.on_cmd_vel(twist)
        assert services.spin_until(lambda: heard['plant: cmd_vel'].level == DiagnosticStatus.STALE, 10.0)
    finally:
        services.close()
