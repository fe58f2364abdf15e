"""The other robots a planner avoids: which robots of the graph count, their odometry, and when they stop counting.

A robot announces itself by publishing its footprint on `<ns>/footprint` from a node of namespace `<ns>`. A
planner follows that robot (subscribes to `<ns>/odom` and avoids it) once the footprint and the odometry have a
publisher, `<ns>` is neither its own namespace nor below it, and odometry has come. From then on the robot is
avoided for as long as the planner runs, since DDS cannot tell a stalled node from one that left: with old
odometry it is avoided where it was last seen, its radius widened by how far it could have coasted; older than
`timeout` it is also reported stale. The radius avoided is the override, else the footprint's, else the
planner's own. The rules in full: docs/robots_and_goals.md.

Fleet is the bookkeeping without ROS (unit-tested alone); RobotFollower is its ROS side in the planner node.
"""

from __future__ import annotations

import functools
import math
import time
import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Iterable, Sequence

from geometry_msgs.msg import PolygonStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message

from fastep_core.planning.others import OtherRobot
from fastep_ros.polled import PolledSubscription, polled
from msg_tools import cdr, convert, interface
from msg_tools.footprint import base_frame, circle_footprint, footprint_radius, polygon_footprint
from msg_tools.interface import LATEST, offered_qos

if TYPE_CHECKING:
    from rclpy.node import Node

__all__ = ['GRAPH_CHECK_TICKS', 'GRAPH_SHARED_FOR', 'Fleet', 'Robot', 'RobotFollower', 'announced',
           'graph_footprint_topics', 'graph_topics', 'namespace_of', 'odometry_reading']

GRAPH_CHECK_TICKS = 8   # the footprint publishers of every known robot are checked every 8th look (2 s)
GRAPH_SHARED_FOR = 0.15  # wall seconds one process's look at the graph's topics serves its other planners


Topics = list[tuple[str, list[str]]]

# Per context (a process's DDS participant): when it last looked, the topics and types it saw, and of those the
# footprint topics.
_topics_seen: weakref.WeakKeyDictionary[Any, tuple[float, Topics, Topics]] = weakref.WeakKeyDictionary()


def _look(node: Any) -> tuple[float, Topics, Topics]:
    context, now = node.context, time.monotonic()
    seen = _topics_seen.get(context)
    if seen is None or now - seen[0] > GRAPH_SHARED_FOR:
        topics = node.get_topic_names_and_types()
        footprints = [(t, types) for t, types in topics if t.endswith('/' + interface.FOOTPRINT)]
        seen = _topics_seen[context] = (now, topics, footprints)
    return seen


def graph_topics(node: Any) -> Topics:
    """node.get_topic_names_and_types(), shared by the nodes of one process for GRAPH_SHARED_FOR: they share one DDS
    participant and its view of the graph. Every planner of a graph layout looked 4 times a second, ~1 ms each
    with 16 robots: 8 % of the process's core, for one answer."""
    return _look(node)[1]


def graph_footprint_topics(node: Any) -> Topics:
    """The footprint topics of graph_topics(node), picked out once per look for the nodes of the process (each
    planner went through every topic of the graph at each look: 16 robots' 300 topics, 2.5 % of a process's CPU
    in lock step)."""
    return _look(node)[2]


def namespace_of(topic: str, leaf: str) -> str | None:
    """The namespace of a topic named `<ns>/<leaf>`: '/r1/footprint' -> '/r1', '/footprint' -> '/'; else None."""
    suffix = '/' + leaf
    if not topic.endswith(suffix):
        return None
    return topic[:-len(suffix)] or '/'


def robot_name(namespace: str) -> str:
    """How a robot is named in status and logs: its namespace without the leading slash ('/' for the root)."""
    return namespace.strip('/') or '/'


def is_own(namespace: str, own: str) -> bool:
    """Whether `namespace` is the planner's own namespace or one below it (its own robot's topics)."""
    if namespace == own:
        return True
    return own != '/' and namespace.startswith(own.rstrip('/') + '/')


def announced(namespace: str, footprint_publishers: Iterable[tuple[str, str]], odom_publishers: int) -> bool:
    """The graph's verdict on a robot: a node of its own namespace publishes its footprint ((node name, node
    namespace) pairs) and its odometry has publishers."""
    return odom_publishers > 0 and any(ns == namespace for _, ns in footprint_publishers)


@dataclass
class Robot:
    """What a planner knows of another robot."""

    namespace: str
    announced: bool = False
    radius: float | None = None          # the footprint's, once received
    position: tuple[float, float] | None = None
    velocity: tuple[float, float] = (0.0, 0.0)
    received: float = -math.inf          # node time of the last odometry
    stamp: float = 0.0                   # its header stamp
    known: bool = False                  # followed once: avoided from then on (the module docstring)

    @functools.cached_property
    def name(self) -> str:
        # Once: a lock-step planner lists its robots by name at every odometry message (N - 1 a tick).
        return robot_name(self.namespace)

    @property
    def odom_topic(self) -> str:
        return self.namespace.rstrip('/') + '/' + interface.ODOM

    @property
    def footprint_topic(self) -> str:
        return self.namespace.rstrip('/') + '/' + interface.FOOTPRINT


class Fleet:
    """The other robots of the graph: who is followed, where they are. No ROS."""

    def __init__(self, own_namespace: str, timeout: float, still_after: float) -> None:
        self.own = own_namespace
        self.timeout = timeout            # dropped beyond this since the last odometry
        self.still_after = still_after    # avoided standing still beyond this
        self.robots: dict[str, Robot] = {}

    def candidates(self, topics: Iterable[tuple[str, Sequence[str]]]) -> list[str]:
        """Namespaces not known yet that have a footprint topic of the interface's type (not the own robot's)."""
        out = []
        for topic, types in topics:
            namespace = namespace_of(topic, interface.FOOTPRINT)
            if namespace is None or namespace in self.robots or is_own(namespace, self.own) or \
                    interface.TYPES[interface.FOOTPRINT] not in types:
                continue
            out.append(namespace)
        return out

    def add(self, namespace: str) -> Robot:
        return self.robots.setdefault(namespace, Robot(namespace))

    def judge(self, namespace: str, verdict: bool) -> bool:
        """Record the graph's verdict on a robot; True if it changed."""
        robot = self.robots[namespace]
        changed = robot.announced != verdict
        robot.announced = verdict
        robot.known = robot.known or (verdict and robot.position is not None)
        return changed

    def heard_footprint(self, namespace: str, radius: float) -> None:
        self.robots[namespace].radius = radius

    def heard_odometry(self, namespace: str, position: tuple[float, float], velocity: tuple[float, float],
                       stamp: float, now: float) -> bool:
        """Take a robot's odometry; True if that made it fresh (it was not followed, or stale, a moment ago)."""
        robot = self.robots[namespace]
        was = self.is_fresh(robot, now)
        robot.position, robot.velocity, robot.received, robot.stamp = position, velocity, now, stamp
        robot.known = robot.known or robot.announced
        return not was and self.is_fresh(robot, now)

    def is_fresh(self, robot: Robot, now: float) -> bool:
        # A time before the last odometry (a clock that went back) counts as fresh: how old it is is not known.
        return robot.known and now - robot.received <= self.timeout

    def followed(self) -> list[Robot]:
        """Every robot avoided: fresh or stale."""
        return [r for r in self.robots.values() if r.known]

    def fresh(self, now: float) -> list[Robot]:
        return [r for r in self.robots.values() if self.is_fresh(r, now)]

    def names(self, now: float) -> list[str]:
        """The robots whose odometry is fresh, sorted (status `others`)."""
        return sorted(r.name for r in self.fresh(now))

    def stale(self, now: float) -> list[Robot]:
        """The robots avoided whose odometry is older than timeout, oldest first."""
        return sorted((r for r in self.followed() if not self.is_fresh(r, now)), key=lambda r: (r.received, r.name))

    def obstacles(self, now: float, radius: Callable[[Robot], float], lag: Callable[[float], float]) \
            -> list[OtherRobot]:
        """The robots followed, as the navigator's OtherRobot, in the order of their names (not of discovery, which
        DDS decides: fastep-sim lists them so too, and the order of a sum decides its last bits): each predicted
        forward by lag(its stamp) at its velocity; once its odometry is older than still_after, still where it
        was last seen (no longer known to move), its radius widened by its last speed times the time since, up to
        timeout (a base whose commands stop brakes: it coasts no further)."""
        out = []
        for robot in sorted(self.followed(), key=lambda r: r.name):
            assert robot.position is not None
            age = now - robot.received
            if age <= self.still_after:
                velocity, ahead, widened = robot.velocity, lag(robot.stamp), 0.0
            else:
                velocity, ahead = (0.0, 0.0), 0.0
                widened = math.hypot(*robot.velocity) * min(age, self.timeout)
            position = (robot.position[0] + velocity[0] * ahead, robot.position[1] + velocity[1] * ahead)
            out.append(OtherRobot(robot.name, position, velocity, radius(robot) + widened))
        return out


def odometry_reading(msg: Odometry | bytes) -> tuple[tuple[float, float], tuple[float, float], float]:
    """(position, map-frame velocity, stamp in seconds) of odometry, a message or its CDR bytes; ValueError if not
    finite (CdrError if the bytes are cut off). The bytes are read with struct (msg_tools.cdr), to the same floats."""
    if isinstance(msg, bytes):
        fields = cdr.odometry_fields(msg)
        if fields is None:   # not little-endian CDR: rclpy reads it
            msg = deserialize_message(msg, Odometry)
        else:
            x, y, qx, qy, qz, qw, vx, vy, _ = fields
            position = (x, y)
            if not (math.isfinite(x) and math.isfinite(y)):
                raise ValueError('odometry position is not finite')
            sec, nanosec = cdr.header_stamp(msg)
            return position, convert.twist_in_map(vx, vy, (qx, qy, qz, qw)), sec + nanosec * 1e-9
    assert not isinstance(msg, bytes)
    return (convert.odometry_position(msg), convert.odometry_velocity(msg),
            convert.stamp_to_seconds(msg.header.stamp))


class RobotFollower:
    """The planner's side of the graph: announces its robot, finds and follows the others (Fleet's ROS side)."""

    def __init__(self, node: Node, own_radius: float, override_radius: float, timeout: float,
                 still_after: float, now: Callable[[], float], on_change: Callable[[], None],
                 on_odometry: Callable[[], None] | None = None, outline: Any = None) -> None:
        """on_odometry: called after each odometry message taken, which then comes in a callback (lock step: a
        planner waits for the others' odometry of a time), not polled; outline: the robot's footprint vertices
        (N, 2) in base_link, announced instead of the circle of own_radius."""
        self.node = node
        self.own_radius = own_radius
        self.override_radius = override_radius
        self.now = now
        self.fleet = Fleet(node.get_namespace(), timeout, still_after)
        self.on_change = on_change
        self.on_odometry = on_odometry
        self.looks = 0
        self.last_names: tuple[list[str], list[str]] = ([], [])
        # Per namespace: how many publishers its footprint had at the last check, and which nodes they were.
        self.footprints: dict[str, tuple[int, list[tuple[str, str]]]] = {}
        self.subscriptions: dict[str, list[Any]] = {}
        self.footprint_pub = node.create_publisher(PolygonStamped, interface.FOOTPRINT,
                                                   offered_qos(interface.FOOTPRINT))
        frame, stamp = base_frame(node.get_namespace()), node.get_clock().now().to_msg()
        self.footprint_pub.publish(circle_footprint(own_radius, frame, stamp) if outline is None else
                                   polygon_footprint(outline, frame, stamp))

    def radius(self, robot: Robot) -> float:
        if self.override_radius > 0.0:
            return self.override_radius
        return robot.radius if robot.radius is not None else self.own_radius

    def discover(self) -> bool:
        """Look at the graph: new robots' footprints, and (every GRAPH_CHECK_TICKS looks, and for new ones) who
        is announced. True if the robots followed changed since the last look (also by odometry going stale)."""
        node = self.node
        new = self.fleet.candidates(graph_footprint_topics(node))
        for namespace in new:
            robot = self.fleet.add(namespace)
            self.subscriptions[namespace] = [node.create_subscription(
                PolygonStamped, robot.footprint_topic, functools.partial(self.on_footprint, namespace),
                offered_qos(interface.FOOTPRINT))]
        every = self.looks % GRAPH_CHECK_TICKS == 0
        check = [ns for ns, robot in self.fleet.robots.items() if every or not robot.announced]
        self.looks += 1
        for namespace in check:
            self.check(namespace)
        names = self.names()
        changed, self.last_names = names != self.last_names, names
        return changed

    def names(self) -> tuple[list[str], list[str]]:
        """The robots whose odometry is fresh (status `others`) and those avoided whose odometry stopped."""
        now = self.now()
        return self.fleet.names(now), [r.name for r in self.fleet.stale(now)]

    def check(self, namespace: str) -> None:
        """Ask the graph whether a robot is (still) announced; follow its odometry from the first time it is."""
        node, robot = self.node, self.fleet.robots[namespace]
        try:
            count = node.count_publishers(robot.footprint_topic)
            seen = self.footprints.get(namespace)
            # Which nodes publish it: asked again only when that may have changed, or when no node of the robot's
            # namespace was among them (DDS can list an endpoint before the node it belongs to is known: its node
            # is then '_NODE_NAMESPACE_UNKNOWN_').
            if seen is None or seen[0] != count or not robot.announced:
                infos = node.get_publishers_info_by_topic(robot.footprint_topic)
                seen = self.footprints[namespace] = (count, [(i.node_name, i.node_namespace) for i in infos])
            # Once its odometry is followed, freshness tells whether it still has a publisher (asking the graph
            # for every robot, every time, cost four times the CPU of the rest of a look with 100 robots).
            subscribed = len(self.subscriptions[namespace]) > 1
            verdict = announced(namespace, seen[1], 1 if subscribed else node.count_publishers(robot.odom_topic))
        except Exception as exc:  # the graph can change under us (rclpy raises its own errors): look again later
            node.get_logger().debug(f'graph look at {namespace} failed: {exc}')
            return
        if not self.fleet.judge(namespace, verdict):
            return
        if verdict and len(self.subscriptions[namespace]) == 1:
            # Taken when used (take: each control tick, each wall tick), not on every 50 Hz message: the N^2
            # fan-in of a graph (fastep_ros.polled). A callback subscription if rclpy cannot make one.
            # In lock step every message is awaited: a callback subscription.
            # Raw: only the pose, twist and stamp are read from the bytes (msg_tools.cdr), N - 1 times a tick.
            taken = polled(node, Odometry, robot.odom_topic, LATEST, raw=True) if self.on_odometry is None else None
            self.subscriptions[namespace].append(taken or node.create_subscription(
                Odometry, robot.odom_topic, functools.partial(self.on_odom, namespace), LATEST, raw=True))
        if verdict:
            node.get_logger().info(f'following robot {robot.name}: {robot.footprint_topic} (from a node of '
                                   f'{namespace}) and {robot.odom_topic} have publishers')
        elif robot.known:
            node.get_logger().warning(f'robot {robot.name} left the graph ({robot.footprint_topic} has no publisher '
                                      f'of {namespace}): avoided where it was last seen')

    def on_footprint(self, namespace: str, msg: PolygonStamped) -> None:
        try:
            self.fleet.heard_footprint(namespace, footprint_radius(msg))
        except ValueError as exc:
            self.node.get_logger().warning(f'ignoring the footprint of {robot_name(namespace)}: {exc}',
                                           throttle_duration_sec=5.0)

    def on_odom(self, namespace: str, msg: Odometry | bytes) -> None:
        """Take another robot's odometry (a message, or its CDR bytes); on_change() if that made it followed
        (status lists it at once)."""
        try:
            position, velocity, stamp = odometry_reading(msg)
        except ValueError as exc:   # msg_tools.cdr.CdrError too
            self.node.get_logger().warning(f'ignoring odometry of {robot_name(namespace)}: {exc}',
                                           throttle_duration_sec=5.0)
            return
        if self.fleet.heard_odometry(namespace, position, velocity, stamp, self.now()):
            self.last_names = self.names()
            self.on_change()
        if self.on_odometry is not None:
            self.on_odometry()

    def take(self) -> None:
        """The newest odometry of every robot whose odometry is polled (fastep_ros.polled), handled as on_odom."""
        for namespace, subscriptions in self.subscriptions.items():
            for sub in subscriptions[1:]:
                if isinstance(sub, PolledSubscription):
                    msg = sub.take_latest()
                    if msg is not None:
                        self.on_odom(namespace, msg)

    def destroy(self) -> None:
        """Destroy every subscription (the polled ones too, which the node does not know) and the footprint's
        publisher: the robot is no longer announced."""
        for subscriptions in self.subscriptions.values():
            for sub in subscriptions:
                if isinstance(sub, PolledSubscription):
                    sub.destroy()
                else:
                    self.node.destroy_subscription(sub)
        self.subscriptions.clear()
        self.node.destroy_publisher(self.footprint_pub)
