"""Exact lock step in the plant and the planner (fastep_ros.lock_step), their callbacks called directly: a step
waits for the command decided at its start, a planner acts once per odometry stamp once the other robots'
odometry of that time is in, whatever order the messages come in."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from geometry_msgs.msg import TwistStamped
from rclpy.parameter import Parameter

from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from fastep_testing.published import keep_published
from msg_tools import convert


def make(cls: type, context: Any, **params: Any) -> Any:
    return cls(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])


def command(vx: float, stamp: float) -> TwistStamped:
    msg = TwistStamped()
    msg.header.stamp = convert.seconds_to_stamp(stamp)
    msg.twist.linear.x = vx
    return msg


def test_a_plant_in_lock_step_integrates_each_step_with_the_command_stamped_at_its_start(context: Any) -> None:
    plant = make(PlantNode, context, start=[0.0, 0.0], rate_hz=20.0, use_sim_time=True, lock_step=True,
                 use_stamped_cmd_vel=True)
    published: list[tuple[float, list[float]]] = []
    plant.publish = lambda: published.append((plant.tick * plant.step, plant.state.tolist()))
    now = [0.0]
    plant.now = lambda: now[0]
    plant.create_publisher(TwistStamped, 'cmd_vel', 10)   # a planner on the graph: its commands are awaited
    try:
        assert plant.locked() and plant.cmd_sub.get_publisher_count() == 1
        plant.on_cmd_vel(command(9.0, 0.0), 0.0)   # sent while time holds at 0: answers no step
        plant.on_timer()
        assert plant.tick is None and published == []
        now[0] = 0.05   # time runs: the first step starts at 0, from the start state, and waits for its command
        plant.on_timer()
        assert plant.tick == 0 and published == [(0.0, [0.0, 0.0])]
        plant.on_cmd_vel(command(1.0, 0.0), 0.0)    # the planner's first command, decided at 0
        assert plant.tick == 1 and published[-1] == (0.05, [pytest.approx(0.05), 0.0])
        now[0] = 0.1
        plant.on_timer()                            # the clock is on, the command of 0.05 is not: the step waits
        assert plant.tick == 1
        plant.on_cmd_vel(command(2.0, 0.05), 0.05)
        assert plant.tick == 2 and published[-1] == (0.1, [pytest.approx(0.15), 0.0])
        now[0] = 0.15
        plant.on_timer()
        assert plant.tick == 2 and plant.waiting_since is not None
        plant.waiting_since -= 10.0                 # its planner silent for LOCK_WAIT of wall time: taken for gone
        plant.on_lock_check()
        assert plant.tick == 3 and plant.planner_gone and published[-1][1][0] == pytest.approx(0.25)
        now[0] = 0.2
        plant.on_timer()                            # no longer waited for, until a command comes again
        assert plant.tick == 4 and published[-1][1][0] == pytest.approx(0.35)
        plant.on_cmd_vel(command(0.0, 0.2), 0.2)
        assert not plant.planner_gone
        now[0] = 0.25
        plant.on_timer()
        assert plant.tick == 5 and published[-1][1][0] == pytest.approx(0.35)   # it stopped
    finally:
        plant.destroy_node()


def test_a_planner_in_lock_step_acts_once_per_stamp_when_the_others_odometry_of_that_time_is_in(
        context: Any) -> None:
    planner = make(PlannerNode, context, workspace=[0.0, 0.0, 20.0, 20.0], use_sim_time=True, lock_step=True,
                   use_stamped_cmd_vel=True)
    sent: list[TwistStamped] = []
    keep_published(planner.cmd_pub, sent.append)
    now = [0.0]
    planner.now = lambda: now[0]
    try:
        assert planner.locked()
        planner.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        planner.robots.fleet.add('/r2')
        planner.robots.fleet.judge('/r2', True)
        planner.robots.on_odom('/r2', convert.state_to_odometry([15.0, 15.0], convert.seconds_to_stamp(0.0)))
        planner.on_goal(convert.point_to_pose_stamped((10.0, 2.0)))
        planner.inputs.on_odom(convert.state_to_odometry([2.0, 2.0], convert.seconds_to_stamp(0.0)))
        assert sent == []                            # the clock holds 0: goals may still be coming
        now[0] = 0.05
        planner.on_control_tick()                    # time runs: the start state is acted on, at 0
        assert [convert.stamp_to_seconds(m.header.stamp) for m in sent] == [0.0] and sent[0].twist.linear.x > 0
        planner.on_control_tick()
        assert len(sent) == 1                        # once
        planner.inputs.on_odom(convert.state_to_odometry([2.1, 2.0], convert.seconds_to_stamp(0.05)))
        assert len(sent) == 1                        # r2's odometry of 0.05 is not in yet
        planner.robots.on_odom('/r2', convert.state_to_odometry([15.0, 14.9], convert.seconds_to_stamp(0.05)))
        assert [convert.stamp_to_seconds(m.header.stamp) for m in sent] == [0.0, 0.05]
        assert np.all(planner.last_command == [sent[-1].twist.linear.x, sent[-1].twist.linear.y])
    finally:
        planner.destroy_node()


def test_a_plant_tells_its_odometry_at_a_rate_of_its_own_on_the_step_grid(context: Any) -> None:
    """Issue 16 item 3: every planner takes every robot's odometry, so on wall time fastep-launch has plants tell it
    at the planners' control rate while they integrate at 50 Hz; each message is the step integrated last."""
    plant = make(PlantNode, context, start=[0.0, 0.0], rate_hz=50.0, odom_rate_hz=20.0)
    stamps: list[float] = []
    plant.publish = lambda: stamps.append(round(plant.tick * plant.step, 9))
    now = [1.0]
    plant.now = lambda: now[0]
    try:
        plant.on_timer()    # the first integration step: told at once
        for k in range(1, 51):   # one second of 50 Hz steps
            now[0] = 1.0 + k * 0.02
            plant.on_timer()
        assert len(stamps) == 21 and stamps[0] == 1.0 and stamps[-1] == 2.0
        assert all(round(s / 0.02, 6).is_integer() for s in stamps)   # whole steps
        assert max(b - a for a, b in zip(stamps, stamps[1:])) <= 0.06 + 1e-9
    finally:
        plant.destroy_node()
