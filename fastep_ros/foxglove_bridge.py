"""fastep-foxglove: a live view of the fastep graph in Foxglove, without a ROS install on the viewing side.

    fastep-foxglove --ros-args [-p port:=8765] [-p host:=127.0.0.1] [-p scene_rate_hz:=10.0]
                    [-p scenario:=table2_s2] [-p robot_radius:=0.5]
    fastep-launch SCENARIO --foxglove 8765        (the same, started with the graph)

Serves the Foxglove WebSocket protocol (foxglove-sdk, protobuf): /fastep/obstacles, /fastep/robots (entity = robot
name), /fastep/plans (`<name>/plan`), /fastep/waypoints (`<name>/waypoint`) as SceneUpdates, /tf (map ->
`<name>/base_link`) and /<name>/scan as a foxglove.LaserScan in the map frame. Robots are found as fastep-record finds
them; sizes from `scenario`, else `robot_radius`. Cheap by construction: the subscriptions belong to an inner node no
executor spins, so a message costs no Python wake-up; every 1 / scene_rate_hz the newest of each is taken and sent
only if a client listens, what changes rarely again when a client subscribes (the protocol keeps nothing for late
joiners). Wall time, not in the lock step. A scan channel added while a viewer is connected can be refused to it (a
foxglove-sdk race: FoxgloveNode.__init__). A port that cannot be bound or a bad parameter: one line, exit 2.
"""

from __future__ import annotations

import math
import re
import threading
from dataclasses import dataclass, field
from typing import Any, Sequence

import foxglove
import numpy as np
from foxglove.channels import FrameTransformsChannel, LaserScanChannel, SceneUpdateChannel
from foxglove.messages import (
    ArrowPrimitive,
    Color,
    CubePrimitive,
    CylinderPrimitive,
    FrameTransform,
    FrameTransforms,
    LaserScan,
    LinePrimitive,
    LinePrimitiveLineType,
    Point3,
    Pose,
    Quaternion,
    SceneEntity,
    SceneUpdate,
    SpherePrimitive,
    TextPrimitive,
    Timestamp,
    Vector3,
)
from foxglove.websocket import ServerListener
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from nav_msgs.msg import Path as PathMsg
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import LaserScan as RosLaserScan
from visualization_msgs.msg import MarkerArray

from fastep_core.errors import FastepError
from fastep_core.geometry import Circle, Segment
from fastep_ros.common import PERIOD_RANGE, RATE_RANGE, StartupError, check_range, declare, node_main
from msg_tools import convert, interface

__all__ = ['CHANNELS', 'FoxgloveNode', 'main']

PROG = 'fastep-foxglove'
OBSTACLES_CHANNEL = '/fastep/obstacles'
ROBOTS_CHANNEL = '/fastep/robots'
PLANS_CHANNEL = '/fastep/plans'
WAYPOINTS_CHANNEL = '/fastep/waypoints'
TF_CHANNEL = '/tf'
CHANNELS = (OBSTACLES_CHANNEL, ROBOTS_CHANNEL, PLANS_CHANNEL, WAYPOINTS_CHANNEL, TF_CHANNEL)
"""The channels served from the start, with the `/<name>/scan` of each robot `scenario` gives a scanner; the
`/<name>/scan` of other robots are added as their scans appear."""

SCAN = 'scan'   # a robot's laser scan (sensor_msgs/LaserScan), published by plants of robots with a sensor
SCAN_TYPE = 'sensor_msgs/msg/LaserScan'
ODOM_TOPIC = re.compile(r'^/([A-Za-z_][A-Za-z0-9_]*)/' + interface.ODOM + '$')

# Tableau 10: a robot's colour by its index in name order (matplotlib's default cycle, as fastep-sim --plot).
PALETTE = np.array([[0x1f, 0x77, 0xb4], [0xff, 0x7f, 0x0e], [0x2c, 0xa0, 0x2c], [0xd6, 0x27, 0x28],
                    [0x94, 0x67, 0xbd], [0x8c, 0x56, 0x4b], [0xe3, 0x77, 0xc2], [0x7f, 0x7f, 0x7f],
                    [0xbc, 0xbd, 0x22], [0x17, 0xbe, 0xcf]]) / 255.0
OBSTACLE_HEIGHT = 0.5   # m: circles are drawn as cylinders this tall, standing on the map plane
ROBOT_HEIGHT = 0.2
# Newest message only: a view shows the present, and keep-last 1 is what makes the polling cheap.
NEWEST = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)


def _stamp(ns: int) -> Timestamp:
    return Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)


def _yaw_quaternion(yaw: float) -> Quaternion:
    return Quaternion(x=0.0, y=0.0, z=math.sin(0.5 * yaw), w=math.cos(0.5 * yaw))


def _pose(x: float, y: float, yaw: float = 0.0, z: float = 0.0) -> Pose:
    return Pose(position=Vector3(x=x, y=y, z=z), orientation=_yaw_quaternion(yaw))


def _color(rgb: np.ndarray, alpha: float = 1.0) -> Color:
    return Color(r=float(rgb[0]), g=float(rgb[1]), b=float(rgb[2]), a=alpha)


def _header_ns(stamp: Any) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


@dataclass
class RobotView:
    """What the view knows of one robot: its inbox subscriptions and the newest of each topic."""

    name: str
    color: np.ndarray
    radius: float
    subs: dict[str, Any] = field(default_factory=dict)   # topic (relative) -> subscription on the inbox node
    pose: tuple[float, float, float] | None = None        # x, y, yaw from odometry
    velocity: tuple[float, float] = (0.0, 0.0)            # map-frame velocity of the reference point (m/s)
    stamp_ns: int = 0                                     # of that odometry
    trailer: tuple[float, float, float] | None = None     # trailer axle x, y, yaw
    plan: list[tuple[float, float]] | None = None
    plan_changed: bool = False
    waypoint: tuple[float, float] | None = None
    waypoint_changed: bool = False
    scan: Any = None                                      # the newest sensor_msgs/LaserScan not sent yet
    scan_channel: LaserScanChannel | None = None

    def placement(self) -> tuple[Any, ...]:
        """What its transform shows: the odometry pose and stamp."""
        return self.stamp_ns, self.pose

    def drawn(self) -> tuple[Any, ...]:
        """What its scene entity shows: pose, stamp, motion and trailer (its radius and colour never change)."""
        return self.stamp_ns, self.pose, self.velocity, self.trailer


class FoxgloveNode(Node):
    """Serves the fastep topics of the live graph to Foxglove clients as scene updates and transforms."""

    def __init__(self, node_name: str = 'foxglove', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        port = declare(self, 'port', 8765, 'TCP port of the Foxglove WebSocket server (0: any free port)',
                       constraints='0 to 65535')
        host = declare(self, 'host', '127.0.0.1', 'address to listen on (0.0.0.0: every interface, for a viewer '
                       'on another computer)')
        rate = declare(self, 'scene_rate_hz', 10.0, 'scene updates and transforms sent per wall second, at most',
                       constraints=f'range [{RATE_RANGE[0]:g}, {RATE_RANGE[1]:g}]')
        discovery_period = declare(self, 'discovery_period', 1.0, 'wall seconds between looks at the graph for new '
                                   'robots and topics',
                                   constraints=f'range [{PERIOD_RANGE[0]:g}, {PERIOD_RANGE[1]:g}]')
        scenario = declare(self, 'scenario', '', 'optional scenario (YAML file or built-in name): the radius of '
                           'each of its robots')
        self.default_radius = declare(self, 'robot_radius', 0.5, 'radius drawn for a robot the scenario does not '
                                      'name (m)', constraints='> 0')
        if not 0 <= port <= 65535:
            raise StartupError(f'parameter port must be in [0, 65535], got {port}')
        check_range('scene_rate_hz', rate, *RATE_RANGE, ' Hz')
        check_range('discovery_period', discovery_period, *PERIOD_RANGE, ' s')
        if not self.default_radius > 0.0:
            raise StartupError(f'parameter robot_radius must be > 0, got {self.default_radius:g}')
        self.radii, scanners = self._scenario_robots(scenario)

        # The inbox: subscriptions nobody spins (see the module docstring); its own name, no remapping.
        self.inbox = Node(f'{self.get_name()}_inbox', context=self.context, use_global_arguments=False,
                          start_parameter_services=False)
        self.obstacles_sub = self.inbox.create_subscription(MarkerArray, interface.OBSTACLES, _ignore,
                                                            interface.LATCHED)
        self.robots: dict[str, RobotView] = {}

        # Every channel known now exists before the server listens, so a client is told of it as it connects.
        # A channel added while a client is connected is advertised to that client before the server records it
        # for the client (foxglove-sdk 0.30.3): a subscription answered at once can be refused ("Unknown channel
        # ID", about 1 in 5 on a loaded machine) and the client then never gets it. Hence the scenario's scanners
        # get their channels here; only the scans of robots the scenario does not name are added later.
        ctx = self.fox_context = foxglove.Context()
        self.obstacles_channel = SceneUpdateChannel(OBSTACLES_CHANNEL, context=ctx)
        self.robots_channel = SceneUpdateChannel(ROBOTS_CHANNEL, context=ctx)
        self.plans_channel = SceneUpdateChannel(PLANS_CHANNEL, context=ctx)
        self.waypoints_channel = SceneUpdateChannel(WAYPOINTS_CHANNEL, context=ctx)
        self.tf_channel = FrameTransformsChannel(TF_CHANNEL, context=ctx)
        self.scan_channels = {name: LaserScanChannel(interface.robot_topic(name, SCAN), context=ctx)
                              for name in scanners}
        self.obstacles: SceneEntity | None = None
        self.obstacles_changed = False
        # What each client-facing view last showed of each robot: a robot is sent again when that changes.
        self.sent_robots: dict[str, tuple[Any, ...]] = {}
        self.sent_transforms: dict[str, tuple[Any, ...]] = {}

        self.resend = threading.Event()   # set from the server's thread when a client subscribes
        try:
            self.server = foxglove.start_server(name='fastep', host=host, port=port, context=ctx,
                                                server_listener=_Listener(self.resend))
        except (RuntimeError, ValueError, OverflowError) as exc:
            self.inbox.destroy_node()
            raise StartupError(f'cannot serve Foxglove on {host}:{port}: {exc}'.splitlines()[0]) from None

        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.discovery_timer = self.create_timer(discovery_period, self.discover, clock=steady)
        self.scene_timer = self.create_timer(1.0 / rate, self.tick, clock=steady)
        self.discover()
        self.get_logger().info(f'serving Foxglove on ws://{host}:{self.port} (Open connection -> Foxglove WebSocket)')

    @property
    def port(self) -> int:
        """The port the server listens on (the one chosen when the parameter was 0)."""
        return int(self.server.port)

    def _scenario_robots(self, source: str) -> tuple[dict[str, float], list[str]]:
        """The radius of each robot the scenario names, and the names of those with a laser scanner."""
        if not source:
            return {}, []
        from fastep_core.scenario import load_scenario
        try:
            robots = load_scenario(source).robots
        except FastepError as exc:
            raise StartupError(f'parameter scenario: {exc}') from None
        return {r.name: float(r.radius) for r in robots}, [r.name for r in robots if r.sensor is not None]

    # ------------------------------------------------------------------------------------------- graph
    def discover(self) -> None:
        """Follow every robot with an odometry topic on the graph; take its trailer_pose and scan when they exist."""
        topics = dict(self.get_topic_names_and_types())
        for topic, types in topics.items():
            match = ODOM_TOPIC.match(topic)
            if match is None or interface.message_type(interface.ODOM) not in types:
                continue
            name = match.group(1)
            robot = self.robots.get(name)
            if robot is None:
                robot = self.robots[name] = RobotView(name, PALETTE[len(self.robots) % len(PALETTE)],
                                                      self.radii.get(name, self.default_radius))
                for relative, msg_type in ((interface.ODOM, Odometry), (interface.PLAN, PathMsg),
                                           (interface.WAYPOINT, PoseStamped)):
                    robot.subs[relative] = self.inbox.create_subscription(
                        msg_type, interface.robot_topic(name, relative), _ignore, self._qos(relative))
                self.get_logger().info(f'showing robot {name}')
            trailer = interface.robot_topic(name, interface.TRAILER_POSE)
            if interface.TRAILER_POSE not in robot.subs and \
                    interface.message_type(interface.TRAILER_POSE) in topics.get(trailer, []):
                robot.subs[interface.TRAILER_POSE] = self.inbox.create_subscription(
                    PoseStamped, trailer, _ignore, NEWEST)
            scan = interface.robot_topic(name, SCAN)
            if SCAN not in robot.subs and SCAN_TYPE in topics.get(scan, []):
                robot.subs[SCAN] = self.inbox.create_subscription(RosLaserScan, scan, _ignore, NEWEST)
                robot.scan_channel = self.scan_channels.get(name)
                if robot.scan_channel is None:
                    robot.scan_channel = self.scan_channels[name] = LaserScanChannel(scan, context=self.fox_context)

    @staticmethod
    def _qos(relative: str) -> QoSProfile:
        # Plans and waypoints come only when they change: reliable, so the one that matters is not lost.
        if relative in (interface.PLAN, interface.WAYPOINT):
            return QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
        return NEWEST

    # ------------------------------------------------------------------------------------------- intake
    @staticmethod
    def _take(sub: Any) -> Any:
        """The newest message waiting on an inbox subscription, or None (what an executor does before a callback)."""
        with sub.handle:
            taken = sub.handle.take_message(sub.msg_type, sub.raw)
        return None if taken is None else taken[0]

    def take_all(self) -> None:
        """Read what came since the last tick: the newest message of every followed topic."""
        msg = self._take(self.obstacles_sub)
        if msg is not None:
            self._take_obstacles(msg)
        for robot in self.robots.values():
            odom = self._take(robot.subs[interface.ODOM])
            if odom is not None:
                try:
                    x, y = convert.odometry_position(odom)
                    yaw = convert.quaternion_to_yaw(odom.pose.pose.orientation)
                    robot.velocity = convert.odometry_velocity(odom)
                except ValueError:
                    pass
                else:
                    if math.isfinite(yaw):
                        robot.pose, robot.stamp_ns = (x, y, yaw), _header_ns(odom.header.stamp)
            plan = self._take(robot.subs[interface.PLAN])
            if plan is not None:   # a planner publishes its plan on every replan: sent only when it differs
                try:
                    waypoints = convert.path_to_waypoints(plan)
                except ValueError:
                    pass
                else:
                    robot.plan_changed |= waypoints != robot.plan
                    robot.plan = waypoints
            waypoint = self._take(robot.subs[interface.WAYPOINT])
            if waypoint is not None:
                try:
                    point = convert.pose_stamped_to_point(waypoint)
                except ValueError:
                    pass
                else:
                    robot.waypoint_changed |= point != robot.waypoint
                    robot.waypoint = point
            if interface.TRAILER_POSE in robot.subs:
                trailer = self._take(robot.subs[interface.TRAILER_POSE])
                if trailer is not None:
                    try:
                        tx, ty = convert.pose_stamped_to_point(trailer)
                        robot.trailer = (tx, ty, convert.trailer_yaw(trailer))
                    except ValueError:
                        pass
            if SCAN in robot.subs:
                scan = self._take(robot.subs[SCAN])
                if scan is not None:
                    robot.scan = scan

    def _take_obstacles(self, msg: MarkerArray) -> None:
        try:
            obstacles = convert.marker_array_to_obstacles(msg)
        except ValueError as exc:
            self.get_logger().warning(f'ignoring /obstacles: {exc}', throttle_duration_sec=5.0)
            return
        circles = [o for o in obstacles if isinstance(o, Circle)]
        segments = [o for o in obstacles if isinstance(o, Segment)]
        grey = Color(r=0.55, g=0.55, b=0.55, a=0.9)
        cylinders = [CylinderPrimitive(pose=_pose(float(c.center[0]), float(c.center[1]), z=0.5 * OBSTACLE_HEIGHT),
                                       size=Vector3(x=2.0 * c.radius, y=2.0 * c.radius, z=OBSTACLE_HEIGHT),
                                       bottom_scale=1.0, top_scale=1.0, color=grey) for c in circles]
        lines = []
        if segments:
            ends = np.array([[s.start, s.end] for s in segments], dtype=float).reshape(-1, 2)
            lines.append(LinePrimitive(type=LinePrimitiveLineType.LineList, pose=_pose(0.0, 0.0), thickness=0.1,
                                       points=[Point3(x=float(x), y=float(y), z=0.0) for x, y in ends],
                                       color=Color(r=0.25, g=0.25, b=0.25, a=1.0)))
        self.obstacles = SceneEntity(timestamp=_stamp(_header_ns(msg.markers[0].header.stamp) if msg.markers else 0),
                                     frame_id=interface.MAP_FRAME, id='obstacles', cylinders=cylinders, lines=lines)
        self.obstacles_changed = True

    # ------------------------------------------------------------------------------------------- output
    def tick(self) -> None:
        """Take the newest messages and send what changed to the clients (nothing is built without a client)."""
        self.take_all()
        resend = self.resend.is_set()
        if resend:
            self.resend.clear()
        if self.obstacles is not None and (self.obstacles_changed or resend) and self.obstacles_channel.has_sinks():
            self.obstacles_channel.log(SceneUpdate(entities=[self.obstacles]))
            self.obstacles_changed = False
        placed = [r for r in self.robots.values() if r.pose is not None]
        # Each view follows what it draws, not the odometry stamp: a trailer pose taken after the robot was
        # sent changes the drawing under the same stamp (and a paused clock keeps stamps still).
        if self.robots_channel.has_sinks():
            changed = [r for r in placed if resend or self.sent_robots.get(r.name) != r.drawn()]
            if changed:
                self.robots_channel.log(SceneUpdate(entities=[self._robot_entity(r) for r in changed]))
                self.sent_robots.update((r.name, r.drawn()) for r in changed)
        if self.tf_channel.has_sinks():
            changed = [r for r in placed if resend or self.sent_transforms.get(r.name) != r.placement()]
            if changed:
                self.tf_channel.log(FrameTransforms(transforms=[self._transform(r) for r in changed]))
                self.sent_transforms.update((r.name, r.placement()) for r in changed)
        plans = [r for r in self.robots.values() if r.plan is not None and (r.plan_changed or resend)]
        if plans and self.plans_channel.has_sinks():
            self.plans_channel.log(SceneUpdate(entities=[self._plan_entity(r) for r in plans]))
            for r in plans:
                r.plan_changed = False
        waypoints = [r for r in self.robots.values() if r.waypoint is not None and (r.waypoint_changed or resend)]
        if waypoints and self.waypoints_channel.has_sinks():
            self.waypoints_channel.log(SceneUpdate(entities=[self._waypoint_entity(r) for r in waypoints]))
            for r in waypoints:
                r.waypoint_changed = False
        for r in placed:
            if r.scan is not None and r.scan_channel is not None:
                if r.scan_channel.has_sinks():
                    r.scan_channel.log(self._scan(r))
                r.scan = None

    @staticmethod
    def _transform(robot: RobotView) -> FrameTransform:
        assert robot.pose is not None
        x, y, yaw = robot.pose
        return FrameTransform(timestamp=_stamp(robot.stamp_ns), parent_frame_id=interface.MAP_FRAME,
                              child_frame_id=f'{robot.name}/base_link', translation=Vector3(x=x, y=y, z=0.0),
                              rotation=_yaw_quaternion(yaw))

    @staticmethod
    def _robot_entity(robot: RobotView) -> SceneEntity:
        """The robot in the map frame at its odometry pose: a disc, a heading arrow, its name, its trailer."""
        assert robot.pose is not None
        x, y, yaw = robot.pose
        r = robot.radius
        color = _color(robot.color, 0.8)
        cylinders = [CylinderPrimitive(pose=_pose(x, y, yaw, 0.5 * ROBOT_HEIGHT),
                                       size=Vector3(x=2.0 * r, y=2.0 * r, z=ROBOT_HEIGHT),
                                       bottom_scale=1.0, top_scale=1.0, color=color)]
        arrows = [ArrowPrimitive(pose=_pose(x, y, yaw, ROBOT_HEIGHT), shaft_length=1.2 * r, shaft_diameter=0.2 * r,
                                 head_length=0.5 * r, head_diameter=0.5 * r, color=Color(r=0.1, g=0.1, b=0.1, a=1.0))]
        texts = [TextPrimitive(pose=_pose(x, y, 0.0, ROBOT_HEIGHT + r), billboard=True, font_size=14.0,
                               scale_invariant=True, color=Color(r=0.0, g=0.0, b=0.0, a=1.0), text=robot.name)]
        cubes, lines = [], []
        vx, vy = robot.velocity
        if vx or vy:   # where it goes in the next second: a point mass's heading stays along +x
            lines.append(LinePrimitive(type=LinePrimitiveLineType.LineStrip, pose=_pose(0.0, 0.0), thickness=0.05,
                                       points=[Point3(x=x, y=y, z=ROBOT_HEIGHT),
                                               Point3(x=x + vx, y=y + vy, z=ROBOT_HEIGHT)],
                                       color=Color(r=0.1, g=0.1, b=0.1, a=0.6)))
        if robot.trailer is not None:
            tx, ty, tyaw = robot.trailer
            cubes.append(CubePrimitive(pose=_pose(tx, ty, tyaw, 0.5 * ROBOT_HEIGHT),
                                       size=Vector3(x=1.5 * r, y=1.5 * r, z=ROBOT_HEIGHT), color=color))
            lines.append(LinePrimitive(type=LinePrimitiveLineType.LineStrip, pose=_pose(0.0, 0.0), thickness=0.1 * r,
                                       points=[Point3(x=x, y=y, z=0.5 * ROBOT_HEIGHT),
                                               Point3(x=tx, y=ty, z=0.5 * ROBOT_HEIGHT)], color=color))
        return SceneEntity(timestamp=_stamp(robot.stamp_ns), frame_id=interface.MAP_FRAME, id=robot.name,
                           cylinders=cylinders, arrows=arrows, texts=texts, cubes=cubes, lines=lines)

    def _plan_entity(self, robot: RobotView) -> SceneEntity:
        assert robot.plan is not None
        xy = [(float(px), float(py)) for px, py in robot.plan]
        color = _color(robot.color, 0.7)
        lines = [LinePrimitive(type=LinePrimitiveLineType.LineStrip, pose=_pose(0.0, 0.0), thickness=0.05,
                               points=[Point3(x=px, y=py, z=0.05) for px, py in xy], color=color)] \
            if len(xy) > 1 else []
        spheres = [SpherePrimitive(pose=_pose(px, py, z=0.05), size=Vector3(x=0.2, y=0.2, z=0.2), color=color)
                   for px, py in xy]
        return SceneEntity(timestamp=_stamp(robot.stamp_ns), frame_id=interface.MAP_FRAME, id=f'{robot.name}/plan',
                           lines=lines, spheres=spheres)

    @staticmethod
    def _waypoint_entity(robot: RobotView) -> SceneEntity:
        assert robot.waypoint is not None
        wx, wy = robot.waypoint
        size = 0.6 * robot.radius
        return SceneEntity(timestamp=_stamp(robot.stamp_ns), frame_id=interface.MAP_FRAME,
                           id=f'{robot.name}/waypoint',
                           spheres=[SpherePrimitive(pose=_pose(wx, wy, z=0.1), size=Vector3(x=size, y=size, z=size),
                                                    color=_color(robot.color, 1.0))])

    @staticmethod
    def _scan(robot: RobotView) -> LaserScan:
        """The scan in the map frame, its origin at the robot's newest pose (zero angle along the heading)."""
        assert robot.pose is not None
        msg = robot.scan
        x, y, yaw = robot.pose
        ranges = np.asarray(msg.ranges, dtype=float)
        start = float(msg.angle_min)
        end = start + float(msg.angle_increment) * max(len(ranges) - 1, 0)
        return LaserScan(timestamp=_stamp(_header_ns(msg.header.stamp)), frame_id=interface.MAP_FRAME,
                         pose=_pose(x, y, yaw, 0.5 * ROBOT_HEIGHT), start_angle=start, end_angle=end,
                         ranges=ranges.tolist(), intensities=list(msg.intensities))

    def destroy_node(self) -> None:
        server = getattr(self, 'server', None)
        if server is not None:
            server.stop()
        inbox = getattr(self, 'inbox', None)
        if inbox is not None:
            inbox.destroy_node()
        super().destroy_node()


def _ignore(msg: Any) -> None:
    """The inbox's callbacks: never called (no executor spins the inbox; FoxgloveNode.take_all reads it)."""


class _Listener(ServerListener):
    """Foxglove server callbacks (on the server's thread): a new subscription asks for everything again."""

    def __init__(self, resend: threading.Event) -> None:
        self.resend = resend

    def on_subscribe(self, client: Any, channel: Any) -> None:
        self.resend.set()


def main(args: Sequence[str] | None = None) -> int:
    return node_main(PROG, FoxgloveNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
