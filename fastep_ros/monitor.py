"""fastep-launch's view of the graph: an rclpy node inside the launcher that sends the goals, follows every robot's
status and odometry, acknowledges each lock-step tick, and looks for another graph on the domain.

Its odometry is taken in bulk from polled subscriptions and read from the bytes (fastep_ros.polled,
msg_tools.cdr): at each /clock before the tick is acknowledged, and at each spin. It spins on the nodes' executor
(fastep_ros.executors). STOP (set by the launcher's SIGINT / SIGTERM handler) ends a spin with KeyboardInterrupt,
between callbacks, never inside rclpy.
"""

from __future__ import annotations

import functools
import math
import os
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fastep_core.scenario import RobotSpec, Scenario
from fastep_ros.errors import GraphConflict

__all__ = ['CONFLICT_CHECK', 'STOP', 'Monitor', 'RobotLive', 'watched_topics']

CONFLICT_CHECK = 1.0    # wall seconds between looks for a graph that joined later

STOP = threading.Event()
"""Set by Ctrl-C or SIGTERM: the run stops at the monitor's next spin and stops every node."""


@dataclass
class RobotLive:
    spec: RobotSpec
    status: dict[str, Any] = field(default_factory=dict)
    rows: list[list[float]] = field(default_factory=list)   # [t, x, y] or [t, x, y, theta0, theta1]
    trailer: float = 0.0
    outcome: str = ''           # '' while running; 'arrived' / 'failed' / 'timeout'
    reason: str = ''
    end_time: float | None = None
    started_at: float | None = None   # planner time of its first status after taking the goal
    activations: int = 0
    escapes: int = 0
    manoeuvres: int = 0
    waypoints: list[list[float]] = field(default_factory=list)

    @property
    def path_length(self) -> float:
        if len(self.rows) < 2:
            return 0.0
        xy = np.array([r[1:3] for r in self.rows])
        return float(np.hypot(*np.diff(xy, axis=0).T).sum())


class Monitor:
    """An rclpy node inside the launcher: sends goals, follows status and odometry of every robot."""

    def __init__(self, scenario: Scenario) -> None:
        import rclpy
        from nav_msgs.msg import Odometry
        from rclpy.serialization import deserialize_message
        from rclpy.signals import SignalHandlerOptions

        from fastep_ros.executors import make_executor
        from msg_tools import cdr, convert

        self.convert, self.cdr = convert, cdr
        self.deserialize, self.odometry_type = deserialize_message, Odometry
        self.odometry: list[tuple[RobotLive, Any]] = []   # (robot, its polled odometry subscription)
        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(args=[], context=self.context, signal_handler_options=SignalHandlerOptions.NO)
        # Wall time: simulated time is read from /clock by follow_clock(), once the goals are in.
        self.node = rclpy.create_node('fastep_launch', context=self.context)
        self.sim_now: float | None = None
        self.recorder_acked = -math.inf   # the latest /clock time fastep-record acknowledged (follow_clock)
        # The node's executor (fastep_ros.executors): a SingleThreadedExecutor rebuilt its wait set of every robot's
        # status, plan and goal endpoints in Python at each wake-up, one per lock-step tick (~0.5 ms of CPU each).
        self.executor = make_executor(None, context=self.context)
        self.executor.add_node(self.node)
        self.robots = {spec.name: RobotLive(spec) for spec in scenario.robots}
        self.goal_pubs: dict[str, Any] = {}
        self.recorded: dict[str, str] = {}
        # topic -> publishers this launch puts on it: more are another graph's.
        self.expected: dict[str, int] = {topic: 0 for topic in watched_topics(scenario)}
        self.checked = -math.inf   # monotonic time of the last look for another graph

    def connect(self) -> None:
        """The monitor's own endpoints: goal publishers, status / odometry / plan subscriptions."""
        from diagnostic_msgs.msg import DiagnosticStatus
        from geometry_msgs.msg import PoseStamped
        from nav_msgs.msg import Odometry
        from nav_msgs.msg import Path as PathMsg
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock

        from msg_tools import interface
        from msg_tools.interface import LATCHED, RELIABLE, offered_qos, robot_topic

        # In lock step the clock waits for this monitor's acknowledgement of each tick, or at a high rtf its odometry
        # queue fell behind the graph and messages were lost (a shorter path, a late arrival).
        self.ack_pub = self.node.create_publisher(Clock, interface.CLOCK_ACK, RELIABLE)
        # What fastep-record (started as /recorder) has received: topic -> message count.
        self.node.create_subscription(DiagnosticStatus, '/recorder/' + interface.RECORDING.removeprefix('~/'),
                                      self.on_recording, interface.STATUS_QOS)
        from fastep_ros.polled import polled

        depth = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)  # every odometry message
        for name, robot in self.robots.items():
            # Latched, so a planner restarted mid-run gets its goal again (it subscribes to latched goals too).
            self.goal_pubs[name] = self.node.create_publisher(PoseStamped, robot_topic(name, interface.GOAL_POSE),
                                                              LATCHED)
            self.node.create_subscription(DiagnosticStatus, robot_topic(name, interface.STATUS),
                                          functools.partial(self.on_status, robot), offered_qos(interface.STATUS))
            # Taken in bulk (drain: at each /clock before it is acknowledged, and at each spin), read from the
            # bytes: an executor wake-up per message cost ~2 ms here and set the pace of a lock step it is part of.
            topic = robot_topic(name, interface.ODOM)
            taken = polled(self.node, Odometry, topic, depth, raw=True)
            if taken is not None:
                self.odometry.append((robot, taken))
            else:
                self.node.create_subscription(Odometry, topic, functools.partial(self.on_odom, robot), depth)
            self.node.create_subscription(PathMsg, robot_topic(name, interface.PLAN),
                                          functools.partial(self.on_plan, robot), RELIABLE)
            if robot.spec.model == 'tractor_trailer':
                self.node.create_subscription(PoseStamped, robot_topic(name, interface.TRAILER_POSE),
                                              functools.partial(self.on_trailer, robot), depth)

    def other_graph(self, launchers: bool = False) -> str:
        """What shows another graph on this domain ('' if nothing): more publishers on /clock, /obstacles, /map or
        a robot's topics than this launch puts there (self.expected), and with `launchers` another fastep-launch.
        (Only before this launch starts its nodes: a second launch that looks and refuses must not stop a first
        one that runs.)"""
        found = []
        if launchers and [n for n, ns in self.node.get_node_names_and_namespaces()
                          if n == self.node.get_name() and ns == '/'][1:]:
            found.append('another fastep-launch')
        for topic, count in self.expected.items():
            have = self.node.count_publishers(topic)
            if have > count:
                found.append(f'{topic} ({have} publishers{f", {count} of them this launch" if count else ""})')
        return ', '.join(found)

    def check_alone(self, launchers: bool = False, now: bool = False) -> None:
        """Once every CONFLICT_CHECK wall seconds (or `now`): a GraphConflict if another graph shares the domain."""
        if time.monotonic() - self.checked < CONFLICT_CHECK and not (launchers or now):
            return
        self.checked = time.monotonic()
        found = self.other_graph(launchers)
        if found:
            domain = os.environ.get('ROS_DOMAIN_ID', '0')
            raise GraphConflict(f'another ROS graph shares ROS_DOMAIN_ID {domain}: {found}; the runs would mix '
                                f'their robots and clocks (stop it, or give each launch its own ROS_DOMAIN_ID)')

    def follow_clock(self, ack_period: float = 0.0, recorder: bool = False) -> None:
        """Subscribe to /clock: the clock, holding the start time until all its subscribers are there,
        starts when this last one joins. Each /clock time taken is acknowledged on clock_ack, one every
        `ack_period` simulated seconds at most; with `recorder`, fastep-record's acknowledgements are followed
        (recorder_acked)."""
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock

        from fastep_ros.lock_step import AckPacer
        from msg_tools.interface import CLOCK, CLOCK_ACK, RELIABLE

        acks = AckPacer(ack_period)

        def on_clock(msg: Any) -> None:
            t = self.convert.stamp_to_seconds(msg.clock)
            self.sim_now = max(self.sim_now or 0.0, t)
            self.drain()
            # Lock step: the clock lets this monitor lag its observer_lag ticks behind at most (it must take every
            # odometry message before its queue is full).
            if acks.due(t):
                self.ack_pub.publish(msg)
        self.node.create_subscription(Clock, CLOCK, on_clock,
                                      QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
        if recorder:
            def on_recorder_ack(msg: Any) -> None:
                self.recorder_acked = max(self.recorder_acked, self.convert.stamp_to_seconds(msg.clock))
            self.node.create_subscription(Clock, '/recorder/' + CLOCK_ACK.removeprefix('~/'), on_recorder_ack,
                                          RELIABLE)

    def now(self) -> float:
        """Simulated time once /clock is followed (0 before its first message; the latest of /clock and the
        odometry stamps), wall time otherwise."""
        if self.sim_now is not None:
            return self.sim_now
        return self.node.get_clock().now().nanoseconds * 1e-9

    def spin(self, seconds: float) -> None:
        """Handle every callback that comes in for `seconds` (spin_once alone handles one, and falls behind)."""
        end = time.monotonic() + seconds
        self.executor.spin_once(timeout_sec=seconds)
        while (left := end - time.monotonic()) > 0 and not STOP.is_set():
            self.executor.spin_once(timeout_sec=left)
        self.drain()
        if STOP.is_set():
            raise KeyboardInterrupt   # here, between spins: never from inside rclpy (see _request_stop)

    def await_recording(self, t: float, seconds: float) -> bool:
        """Spin until fastep-record has acknowledged simulated time `t` (follow_clock with `recorder`), for
        `seconds` wall seconds at most, also after Ctrl-C (STOP); True if it has. In lock step the recorder may lag
        the clock's observer_lag ticks behind: the nodes are stopped after this, and what it has not taken by then
        would not be in the file."""
        end = time.monotonic() + seconds
        while self.recorder_acked < t - 1e-6 and (left := end - time.monotonic()) > 0:
            self.executor.spin_once(timeout_sec=min(left, 0.01))
        return self.recorder_acked >= t - 1e-6

    def close(self) -> None:
        for _, subscription in self.odometry:
            subscription.destroy()
        self.odometry.clear()
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)

    def on_status(self, robot: RobotLive, msg: Any) -> None:
        robot.status = self.convert.diagnostic_to_dict(msg)
        if robot.started_at is None and robot.status.get('message') in ('kinematic', 'avoiding'):
            try:
                robot.started_at = float(robot.status.get('since', robot.status['t']))
            except (KeyError, ValueError):
                pass
        for key in ('activations', 'escapes', 'manoeuvres'):
            try:
                setattr(robot, key, int(robot.status.get(key, 0)))
            except ValueError:
                pass

    def on_recording(self, msg: Any) -> None:
        self.recorded = self.convert.diagnostic_to_dict(msg)

    def drain(self) -> None:
        """Take every odometry message received (polled subscriptions, no wake-up per message)."""
        for robot, subscription in self.odometry:
            for data in subscription.take_all():
                self.on_odom(robot, data)

    def on_odom(self, robot: RobotLive, msg: Any) -> None:
        """Odometry (a message, or its CDR bytes) into the robot's rows."""
        if isinstance(msg, bytes):
            try:
                fields = self.cdr.odometry_fields(msg)
                sec, nanosec = self.cdr.header_stamp(msg)
            except ValueError:   # cut off
                return
            if fields is None:   # not little-endian CDR
                msg = self.deserialize(msg, self.odometry_type)
            else:
                x, y, qx, qy, qz, qw = fields[:6]
                self.add_row(robot, sec + nanosec * 1e-9, x, y, (qx, qy, qz, qw))
                return
        q = msg.pose.pose.orientation
        self.add_row(robot, self.convert.stamp_to_seconds(msg.header.stamp), msg.pose.pose.position.x,
                     msg.pose.pose.position.y, (q.x, q.y, q.z, q.w))

    def add_row(self, robot: RobotLive, t: float, x: float, y: float,
                orientation: tuple[float, float, float, float]) -> None:
        if not (math.isfinite(x) and math.isfinite(y)):
            return
        if self.sim_now is not None:
            # Odometry is stamped with simulated time and comes reliably; /clock is best effort, and on a loaded
            # machine this monitor has gone 30 s without a /clock message while the robots drove on (it then
            # took the run for stalled). Either shows that time goes on.
            self.sim_now = max(self.sim_now, t)
        if robot.rows and t <= robot.rows[-1][0]:
            return
        if robot.spec.model in ('tractor_trailer', 'diff_drive'):
            try:
                yaw = self.convert.yaw_of(*orientation)
            except ValueError:
                return
            # rows [t, x, y, theta] for a diff drive, as fastep-sim's, and [t, x, y, theta0, theta1]
            robot.rows.append([t, x, y, yaw, robot.trailer] if robot.spec.model == 'tractor_trailer' else
                              [t, x, y, yaw])
        else:
            robot.rows.append([t, x, y])

    def on_trailer(self, robot: RobotLive, msg: Any) -> None:
        try:
            robot.trailer = self.convert.trailer_yaw(msg)
        except ValueError:
            pass

    def on_plan(self, robot: RobotLive, msg: Any) -> None:
        points = self.convert.path_to_waypoints(msg)
        robot.waypoints = [list(p) for p in points[:-1]]  # the last pose is the goal

    def send_goals(self) -> None:
        for name, robot in self.robots.items():
            goal = self.convert.point_to_pose_stamped(robot.spec.goal, self.node.get_clock().now().to_msg(),
                                                      yaw=robot.spec.goal_heading or 0.0)
            self.goal_pubs[name].publish(goal)


def watched_topics(scenario: Scenario, sim_time: bool = True) -> dict[str, int]:
    """The topics another graph on the domain would be seen on, and how many publishers this launch puts there."""
    from msg_tools.interface import CLOCK, CMD_VEL, GOAL_POSE, MAP, OBSTACLES, ODOM, STATUS, TRAILER_POSE, robot_topic

    out = {CLOCK: int(sim_time), OBSTACLES: 1, MAP: 1}
    for spec in scenario.robots:
        topics = (ODOM, CMD_VEL, GOAL_POSE, STATUS) + ((TRAILER_POSE,) if spec.model == 'tractor_trailer' else ())
        out.update((robot_topic(spec.name, topic), 1) for topic in topics)
    return out
