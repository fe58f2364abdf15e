"""Speed limits never lift by arithmetic: a positive nav2_msgs/SpeedLimit is a positive cap the robot keeps (5e-324 %
of max_speed was 0, which means unlimited: the robot drove on at full speed; with dwa a traceback, and the old limit
kept), the cap is on status, and a flood of changes is a bounded number of log lines, the latest said."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from rclpy.serialization import deserialize_message

from fastep_ros.planner import PlannerNode
from fastep_testing.in_process import ObedientBase, planner_node
from msg_tools import convert

SpeedLimit = pytest.importorskip('nav2_msgs.msg', reason='nav2_msgs is built by make (interfaces/build.sh)').SpeedLimit

def make(context: Any, **params: Any) -> PlannerNode:
    overrides = {'workspace': [0.0, 0.0, 100.0, 20.0], 'model': 'diff_drive', 'robot_radius': 0.3, **params}
    return planner_node(context, **overrides)


def status_values(node: PlannerNode) -> dict[str, Any]:
    """The key/values of the status the node publishes now."""
    sent: list[bytes] = []
    publisher = node.reports.status_pub
    real = publisher.publish

    def recorded(msg: bytes) -> None:
        sent.append(msg)
        real(msg)
    publisher.publish = recorded   # what is sent
    try:
        node.reports.publish(force=True)
    finally:
        publisher.publish = real   # as it was
    from diagnostic_msgs.msg import DiagnosticStatus
    assert len(sent) == 1
    return convert.diagnostic_to_dict(deserialize_message(sent[0], DiagnosticStatus))


@pytest.mark.parametrize('algorithm', ['fastep', 'dwa'])
def test_an_underflowing_percentage_caps_the_robot_at_a_tiny_positive_speed(context: Any, algorithm: str,
                                                                            capfd: pytest.CaptureFixture[str]) -> None:
    node = make(context, algorithm=algorithm)
    try:
        base = ObedientBase(node)
        speeds = [base.tick() for _ in range(40)]
        assert speeds[-1] > 0.5   # under way
        node.on_speed_limit(SpeedLimit(percentage=True, speed_limit=5e-324))
        cap = node.params.max_speed
        assert 0.0 < cap <= 1e-6   # a positive cap, tiny: 5e-324 % of 1 m/s is below any speed a robot has
        speeds = [base.tick() for _ in range(40)]   # braking at max_acceleration (2.5 m/s^2): 0.4 s at most
        nav, control = node.navigator, node.control_tick
        assert nav is not None and control is not None
        assert nav.limits.max_speed == control.smoother.max_speed == cap   # the cap reached the navigator too
        assert all(math.isfinite(v) for v in speeds) and max(speeds[-20:]) <= cap * (1 + 1e-9)
        assert np.isfinite(base.state).all()
        said = capfd.readouterr().err
        assert 'Traceback' not in said and 'planning thread' not in said
        assert f'speed limit: max_speed {cap:g} m/s' in said
    finally:
        node.destroy_node()


def test_the_status_shows_the_speed_cap_in_m_s_and_nothing_without_a_limit(context: Any) -> None:
    node = make(context, max_speed=2.0)
    try:
        base = ObedientBase(node)
        base.tick()
        assert 'speed_limit' not in status_values(node)
        node.on_speed_limit(SpeedLimit(percentage=True, speed_limit=25.0))
        assert float(status_values(node)['speed_limit']) == pytest.approx(0.5)
        node.on_speed_limit(SpeedLimit(percentage=False, speed_limit=5e-324))
        assert 0.0 < float(status_values(node)['speed_limit']) <= 1e-6
        node.on_speed_limit(SpeedLimit(percentage=False, speed_limit=3.0))   # above max_speed: capped at it
        assert float(status_values(node)['speed_limit']) == pytest.approx(2.0)
        node.on_speed_limit(SpeedLimit(percentage=True, speed_limit=0.0))    # lifted
        assert 'speed_limit' not in status_values(node)
    finally:
        node.destroy_node()


def test_a_flood_of_speed_limit_changes_is_a_bounded_number_of_log_lines_saying_the_latest(
        context: Any, capfd: pytest.CaptureFixture[str]) -> None:
    node = make(context, planning_thread=False)
    now = [0.0]   # the line's wall clock, the test's: the 1000 changes come within a period however busy the machine
    node.speed_limit_line.clock = lambda: now[0]
    try:
        capfd.readouterr()
        for k in range(1000):   # alternating, as two speed filters fighting over the topic
            node.on_speed_limit(SpeedLimit(percentage=True, speed_limit=25.0 if k % 2 else 50.0))
        assert node.params.max_speed == pytest.approx(0.25)   # every change taken: the newest is in force
        lines = [line for line in capfd.readouterr().err.splitlines() if 'speed limit' in line]
        assert 1 <= len(lines) <= 2, lines
        assert 'max_speed 0.5 m/s' in lines[0]   # the first change said at once
        # Once the period is over the newest cap is said, with how many changes came meanwhile.
        now[0] += node.speed_limit_line.period
        node.speed_limit_line.flush()
        lines = [line for line in capfd.readouterr().err.splitlines() if 'speed limit' in line]
        assert len(lines) == 1 and 'max_speed 0.25 m/s' in lines[0] and '999 changes' in lines[0], lines
        now[0] += node.speed_limit_line.period
        node.speed_limit_line.flush()   # nothing new: nothing said
        assert not [line for line in capfd.readouterr().err.splitlines() if 'speed limit' in line]
    finally:
        node.destroy_node()
