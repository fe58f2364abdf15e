"""Hostile /clock messages and clock jumps (issue "Hardening", items 1 and 2): the nodes are built in this process
on a free domain and fed /clock over DDS by a publisher in the same context."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from nav_msgs.msg import Odometry
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock

from fastep_core.geometry import Circle
from fastep_core.world import World
from fastep_ros.common import CLOCK_JUMP_LIMIT
from fastep_ros.map_server import MapNode
from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from fastep_ros.recorder import RecorderNode
from fastep_testing.graph import ONE_CIRCLE, write
from fastep_testing.published import keep_published
from msg_tools import convert

S, MS = 1_000_000_000, 1_000_000   # nanoseconds


def make(cls: type, context: Any, **params: Any) -> Any:
    return cls(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])


class Graph:
    """Nodes in one executor and a /clock publisher beside them."""

    def __init__(self, context: Any, nodes: list[Any]) -> None:
        import rclpy
        self.nodes = nodes
        self.driver = rclpy.create_node('clock_driver', context=context)
        self.pub = self.driver.create_publisher(Clock, '/clock', 10)
        self.executor = SingleThreadedExecutor(context=context)
        for node in [*nodes, self.driver]:
            self.executor.add_node(node)

    def spin_until(self, done: Callable[[], bool], seconds: float = 10.0) -> bool:
        end = time.monotonic() + seconds
        while not done() and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.02)   # a node's exception would come out of here
        return done()

    def wait_matched(self) -> None:
        assert self.spin_until(lambda: self.pub.get_subscription_count() >= len(self.nodes))

    def send(self, sec: int, nanosec: int = 0) -> None:
        self.pub.publish(Clock(clock=TimeMsg(sec=sec, nanosec=nanosec)))

    def times(self) -> list[int]:
        """Every node's clock, nanoseconds."""
        return [node.get_clock().now().nanoseconds for node in self.nodes]

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        for node in [*self.nodes, self.driver]:
            node.destroy_node()


def test_a_bad_or_lone_far_clock_message_is_ignored_and_kills_no_node(context: Any, tmp_path: Path) -> None:
    """sec = -1 is valid on the wire (int32) but rclpy raised "Seconds value must not be negative" inside the
    executor: the map, plant, planner and recorder died. A lone sec = 2^31 - 1 froze the plant for good."""
    scenario = write(tmp_path / 'one.yaml', ONE_CIRCLE)
    nodes = [make(MapNode, context, scenario=str(scenario), use_sim_time=True),
             make(PlantNode, context, start=[2.0, 10.0], use_sim_time=True),
             make(PlannerNode, context, workspace=[0.0, 0.0, 20.0, 20.0], use_sim_time=True),
             make(RecorderNode, context, output=str(tmp_path / 'r.mcap'), use_sim_time=True)]
    graph = Graph(context, nodes)
    try:
        graph.wait_matched()
        graph.send(5)
        assert graph.spin_until(lambda: graph.times() == [5 * S] * 4)
        for sec, nanosec in ((-1, 0), (-2**31, 0), (6, 1_000_000_000), (2**31 - 1, 0), (4, 0)):
            graph.send(sec, nanosec)
            graph.spin_until(lambda: False, 0.2)
            assert graph.times() == [5 * S] * 4, (sec, nanosec)
        graph.send(5, 50_000_000)   # the clock goes on: the lone jump (and the lone step back) were ignored
        assert graph.spin_until(lambda: graph.times() == [5 * S + 50 * MS] * 4)
        graph.send(20)   # ahead, but within CLOCK_JUMP_LIMIT: taken at once
        assert graph.spin_until(lambda: graph.times() == [20 * S] * 4)
        far = 20 + int(CLOCK_JUMP_LIMIT) + 1
        graph.send(far)   # a real jump (a replay of another run) is taken once the next message confirms it
        graph.spin_until(lambda: False, 0.2)
        assert graph.times() == [20 * S] * 4
        graph.send(far, 50_000_000)
        assert graph.spin_until(lambda: graph.times() == [far * S + 50 * MS] * 4)
        graph.send(1)   # so is a restarted clock
        graph.spin_until(lambda: False, 0.2)
        graph.send(1, 50_000_000)
        assert graph.spin_until(lambda: graph.times() == [S + 50 * MS] * 4)
    finally:
        graph.close()


def test_after_a_clock_jump_the_plant_goes_on_and_the_planner_never_acts_on_a_position_left(context: Any) -> None:
    """A clock that really went far ahead and back (each confirmed): the plant integrated one step at the far
    time; back at the old time it must go on integrating (it waited for the old time to pass the far one: no
    odometry ever again), and the planner must hold the robot while its odometry is stamped ahead of its clock or
    came after it (it went on 'kinematic' with a frozen position, or 'arrived' for a robot that had not)."""
    plant = make(PlantNode, context, start=[2.0, 10.0], use_sim_time=True)
    planner = make(PlannerNode, context, workspace=[0.0, 0.0, 20.0, 20.0], use_sim_time=True)
    sent: list[Odometry] = []
    keep_published(plant.odom_pub, sent.append)
    clock = planner.get_clock()
    from rclpy.time import Time

    def planner_at(t: float) -> None:
        clock.set_ros_time_override(Time(nanoseconds=int(round(t * 1e9)), clock_type=clock.clock_type))
    try:
        world = World.from_obstacles([0, 0, 20, 20], [Circle((10.0, 10.0), 1.5)])
        planner.inputs.on_obstacles(convert.obstacles_to_marker_array(world.obstacle_list))
        planner_at(1.0)
        planner.on_goal(convert.point_to_pose_stamped((18.0, 10.5)))
        assert plant.advance(1.0) and plant.advance(3.0)
        far = 2.0**31 - 1
        assert plant.advance(far)   # the gap is not integrated
        plant.publish()
        assert convert.stamp_to_seconds(sent[-1].header.stamp) == far
        planner_at(3.02)
        planner.inputs.on_odom(sent[-1])   # odometry from the far time, at the planner's old time
        planner.on_control()
        assert planner.reports.status()[1] == 'stale' and 'ahead of this node\'s clock' in planner.reports.status()[2]
        planner_at(far)
        planner.inputs.on_odom(sent[-1])
        planner_at(3.04)   # the clock went back after the odometry came
        planner.on_control()
        assert planner.reports.status()[1] == 'stale' and 'clock went back' in planner.reports.status()[2]
        assert plant.advance(3.04), 'back at the old time the plant goes on'
        assert plant.tick is not None and abs(plant.tick * plant.step - 3.04) < 1e-9
        plant.on_cmd_vel(convert.command_to_twist(np.array([1.0, 0.0]), 'point_mass'))
        assert plant.advance(3.5)
        plant.publish()
        assert convert.stamp_to_seconds(sent[-1].header.stamp) == 3.5
        planner_at(3.5)
        planner.inputs.on_odom(sent[-1])
        planner.on_control()
        assert planner.reports.status()[1] in ('kinematic', 'avoiding'), planner.reports.status()
    finally:
        planner.destroy_node()
        plant.destroy_node()
