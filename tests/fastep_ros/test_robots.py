"""Other robots: only robots that announce themselves (footprint from a node of their namespace, odometry with a
publisher) are followed; never the planner's own robot; dropped when their odometry goes stale.

The bookkeeping (fastep_ros.robots.Fleet) alone, then a planner node in this process with fake robots beside it
(each in its own namespace, as a real robot's nodes would be), over DDS on an isolated domain."""

from __future__ import annotations

import time
from typing import Any, Callable, Iterator

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PolygonStamped
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter

from fastep_ros.planner import PlannerNode
from fastep_ros.robots import Fleet, announced, namespace_of
from msg_tools import convert
from msg_tools.convert import diagnostic_to_dict
from msg_tools.footprint import circle_footprint
from msg_tools.interface import LATCHED, RELIABLE, STATUS_QOS

FOOTPRINT = 'geometry_msgs/msg/PolygonStamped'


# ----------------------------------------------------------------------------------------------- bookkeeping

def test_candidates_are_announced_namespaces_other_than_the_own_robot_s() -> None:
    fleet = Fleet('/d1', timeout=3.0, still_after=1.0)
    topics = [('/d1/footprint', [FOOTPRINT]),                  # its own announcement
              ('/d1/diff_drive_controller/footprint', [FOOTPRINT]),   # below its own namespace: its own base
              ('/d1/odom', ['nav_msgs/msg/Odometry']),
              ('/r2/footprint', [FOOTPRINT]), ('/fleet/r3/footprint', [FOOTPRINT]),
              ('/r4/footprint', ['std_msgs/msg/String']),      # not a footprint
              ('/r5/odom', ['nav_msgs/msg/Odometry'])]         # odometry alone announces nothing
    assert fleet.candidates(topics) == ['/r2', '/fleet/r3']
    root = Fleet('/', timeout=3.0, still_after=1.0)
    assert root.candidates([('/footprint', [FOOTPRINT]), ('/r2/footprint', [FOOTPRINT])]) == ['/r2']
    assert namespace_of('/footprint', 'footprint') == '/' and namespace_of('/r1/odom', 'footprint') is None


def test_the_graph_verdict_needs_the_robot_s_own_footprint_publisher_and_an_odometry_publisher() -> None:
    assert announced('/r2', [('planner', '/r2')], odom_publishers=1)
    assert not announced('/r2', [('planner', '/r2')], odom_publishers=0)       # a planner with no plant
    assert not announced('/r2', [('replay', '/')], odom_publishers=1)          # republished from elsewhere
    assert not announced('/r2', [], odom_publishers=1)


def test_a_robot_is_followed_once_announced_and_kept_where_last_seen_when_its_odometry_stops() -> None:
    """Issue "Faults", item 1: a robot whose odometry stops (its plant stalled) or whose node leaves the graph stays
    where it was last seen, its radius widened by how far it could coast at its last speed; it was dropped after
    `timeout` and driven through."""
    fleet = Fleet('/r1', timeout=3.0, still_after=1.0)
    fleet.add('/r2')
    assert fleet.heard_odometry('/r2', (5.0, 5.0), (1.0, 0.0), stamp=10.0, now=10.0) is False  # not announced
    assert fleet.names(10.0) == [] and fleet.followed() == []
    assert fleet.judge('/r2', True)
    assert fleet.names(10.0) == ['r2']
    radius = lambda robot: 0.4 if robot.radius is None else robot.radius  # noqa: E731
    no_lag = lambda stamp: 0.0  # noqa: E731
    [other] = fleet.obstacles(10.5, radius, no_lag)
    assert other.position == (5.0, 5.0) and other.velocity == (1.0, 0.0) and other.radius == 0.4
    fleet.heard_footprint('/r2', 0.7)
    [other] = fleet.obstacles(11.5, radius, no_lag)
    # still there, no longer known to move: anywhere it could have got to at 1 m/s in 1.5 s
    assert other.position == (5.0, 5.0) and other.velocity == (0.0, 0.0) and other.radius == pytest.approx(2.2)
    assert fleet.stale(11.5) == []
    [other] = fleet.obstacles(60.0, radius, no_lag)   # stale: kept, coasting no further than `timeout`
    assert other.position == (5.0, 5.0) and other.radius == pytest.approx(3.7)
    assert fleet.names(60.0) == [] and [r.name for r in fleet.stale(60.0)] == ['r2']
    assert fleet.heard_odometry('/r2', (6.0, 5.0), (0.0, 0.0), stamp=70.0, now=70.0) is True   # fresh again
    [other] = fleet.obstacles(70.0, radius, lambda stamp: 0.1)
    assert other.position == (6.0, 5.0) and other.radius == 0.7 and fleet.stale(70.0) == []
    assert fleet.judge('/r2', False)   # its publishers left the graph (or its node stalled past its lease)
    [other] = fleet.obstacles(200.0, radius, no_lag)
    assert other.position == (6.0, 5.0) and other.radius == 0.7   # parked: kept exactly where it stood


# ----------------------------------------------------------------------------------------------- over DDS

class World:
    """A planner node `/d1` and the fake robots' nodes of a test, spun together."""

    def __init__(self, context: Any, **params: Any) -> None:
        from rclpy.executors import SingleThreadedExecutor
        self.context = context
        # Every control tick plans: the test's clock decides when (the planning thread: test_planning_thread.py).
        overrides = [Parameter('workspace', value=[0.0, 0.0, 20.0, 20.0]), Parameter('max_speed', value=1.0),
                     Parameter('planning_thread', value=False), *(Parameter(k, value=v) for k, v in params.items())]
        self.planner = PlannerNode(context=context, namespace='/d1', parameter_overrides=overrides)
        self.planner.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.planner)
        self.nodes: list[Any] = []

    def node(self, name: str, namespace: str) -> Any:
        import rclpy
        node = rclpy.create_node(name, namespace=namespace, context=self.context)
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def spin_until(self, predicate: Callable[[], bool], timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                raise AssertionError(f'timed out after {timeout:g} s waiting for {what}')
            self.executor.spin_once(timeout_sec=0.02)

    def spin_for(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)

    def others(self) -> list[str]:
        return sorted(o.name for o in self.planner.inputs.other_robots(self.planner.now()))

    def close(self) -> None:
        self.executor.shutdown()
        for node in [*self.nodes, self.planner]:
            node.destroy_node()


@pytest.fixture
def world(context: Any) -> Iterator[World]:
    w = World(context, other_robot_timeout=1.5)
    try:
        yield w
    finally:
        w.close()


def odometry(x: float, y: float, vx: float = 0.0) -> Odometry:
    msg = convert.state_to_odometry([x, y])
    msg.twist.twist.linear.x = vx
    return msg


def test_the_planner_announces_its_footprint(world: World) -> None:
    heard: list[PolygonStamped] = []
    world.node('listener', '/').create_subscription(PolygonStamped, '/d1/footprint', heard.append, LATCHED)
    world.spin_until(lambda: bool(heard), 20.0, 'the latched footprint')
    assert heard[0].header.frame_id == 'd1/base_link' and len(heard[0].polygon.points) == 16


def test_its_own_base_s_odometry_is_not_another_robot_and_the_robot_drives_at_full_speed(world: World) -> None:
    """ros2_control's diff_drive_controller publishes `<ns>/diff_drive_controller/odom`: the robot avoided
    itself there, and 1.0 m/s fell to 0.2."""
    controller = world.node('controller_manager', '/d1')
    pub = controller.create_publisher(Odometry, 'diff_drive_controller/odom', RELIABLE)
    planner = world.planner
    planner.inputs.on_odom(odometry(2.0, 2.0))
    planner.on_goal(convert.point_to_pose_stamped((15.0, 15.0)))
    heard: list[Odometry] = []
    world.node('listener', '/').create_subscription(Odometry, '/d1/diff_drive_controller/odom', heard.append,
                                                    RELIABLE)

    def published() -> bool:
        pub.publish(odometry(2.0, 2.0))
        return len(heard) >= 3 and planner.wall_ticks >= 2
    world.spin_until(published, 20.0, 'the controller odometry to be on the graph and heard')
    world.spin_for(0.6)   # two more looks at the graph, with the controller still publishing
    pub.publish(odometry(2.0, 2.0))
    world.spin_for(0.1)
    planner.inputs.on_odom(odometry(2.0, 2.0))
    planner.on_control()
    assert float(np.hypot(*planner.last_command)) == pytest.approx(1.0, abs=0.05)
    assert world.others() == []
    assert '/d1/diff_drive_controller/odom' not in {s.topic_name for s in planner.subscriptions}


def test_a_planner_with_no_plant_and_a_replayed_robot_are_not_followed(world: World) -> None:
    # A planner without a plant: its footprint (and its odometry subscription) are on the graph, no odometry.
    lonely = PlannerNode(context=world.context, namespace='/r3')
    world.nodes.append(lonely)
    world.executor.add_node(lonely)
    # A replay-like node in the root namespace republishing a robot's footprint and odometry.
    replay = world.node('replay', '/')
    replay.create_publisher(PolygonStamped, '/r4/footprint', LATCHED).publish(circle_footprint(0.5, 'r4/base_link'))
    odom = replay.create_publisher(Odometry, '/r4/odom', RELIABLE)
    heard: list[Odometry] = []
    world.node('listener', '/').create_subscription(Odometry, '/r4/odom', heard.append, RELIABLE)

    def seen() -> bool:
        odom.publish(odometry(5.0, 5.0))
        topics = {name for name, _ in world.planner.get_topic_names_and_types()}
        return bool(heard) and {'/r3/status', '/r3/odom', '/r4/footprint'} <= topics
    world.spin_until(seen, 20.0, 'the lonely planner and the replay on the graph')
    world.spin_for(2.2)   # a full check of the graph (every eighth look; new robots are checked at once)
    assert world.others() == []
    subscribed = {s.topic_name for s in world.planner.subscriptions}
    assert '/r3/odom' not in subscribed and '/r4/odom' not in subscribed


def test_an_announced_robot_is_followed_kept_stale_when_its_odometry_stops_and_fresh_when_it_comes(
        world: World) -> None:
    heard: list[DiagnosticStatus] = []
    robot = world.node('planner', '/r2')   # stands for r2's planner (the footprint) and its plant (odometry)
    robot.create_publisher(PolygonStamped, 'footprint', LATCHED).publish(circle_footprint(0.8, 'r2/base_link'))
    odom = robot.create_publisher(Odometry, 'odom', RELIABLE)

    def followed() -> bool:
        odom.publish(odometry(5.0, 5.0, vx=0.5))
        return world.others() == ['r2'] and world.planner.robots.fleet.names(world.planner.now()) == ['r2']
    world.spin_until(followed, 20.0, 'r2 to be followed')
    statuses = world.node('monitor', '/').create_subscription(DiagnosticStatus, '/d1/status', heard.append,
                                                              STATUS_QOS)
    world.spin_until(lambda: any(diagnostic_to_dict(m).get('others') == 'r2' for m in heard), 20.0,
                     'status to list r2')
    # Its odometry stops (a stalled plant): after other_robot_timeout it is stale, and still avoided where it was.
    heard.clear()
    world.spin_until(lambda: any(diagnostic_to_dict(m).get('stale') == 'r2' and diagnostic_to_dict(m)['others'] == ''
                                 for m in heard), 20.0, 'status to list r2 as stale')
    [other] = world.planner.inputs.other_robots(world.planner.now())
    assert other.name == 'r2' and other.velocity == (0.0, 0.0) and other.position == pytest.approx((5.0, 5.0))
    assert other.radius == pytest.approx(0.8 + 0.5 * 1.5, abs=1e-6)   # its reach: 0.5 m/s for other_robot_timeout
    world.spin_until(followed, 20.0, 'r2 to be followed again')
    assert statuses is not None
    [other] = world.planner.inputs.other_robots(world.planner.now())
    assert other.radius == pytest.approx(0.8, abs=1e-6) and other.velocity == (0.5, 0.0)


class _Context:
    """A stand-in for an rclpy Context: an object of its own."""


class _GraphStub:
    """The few node calls RobotFollower makes, over a graph the test writes."""

    def __init__(self) -> None:
        from types import SimpleNamespace
        self.ns = SimpleNamespace
        self.topics: list[tuple[str, list[str]]] = []
        self.publishers: dict[str, list[tuple[str, str]]] = {}
        self.subscribed: list[str] = []
        self.context = _Context()   # a process of its own: its look at the graph is its own (graph_topics)

    def get_namespace(self) -> str:
        return '/d1'

    def get_clock(self) -> Any:
        from rclpy.clock import Clock
        return Clock()

    def get_logger(self) -> Any:
        return self.ns(info=lambda *a, **k: None, debug=lambda *a, **k: None, warning=lambda *a, **k: None)

    def create_publisher(self, *args: Any) -> Any:
        return self.ns(publish=lambda msg: None)

    def create_subscription(self, msg_type: Any, topic: str, *args: Any, **kwargs: Any) -> Any:
        self.subscribed.append(topic)
        return topic

    def get_topic_names_and_types(self) -> list[tuple[str, list[str]]]:
        return self.topics

    def count_publishers(self, topic: str) -> int:
        return len(self.publishers.get(topic, []))

    def get_publishers_info_by_topic(self, topic: str) -> list[Any]:
        return [self.ns(node_name=n, node_namespace=ns) for n, ns in self.publishers.get(topic, [])]


def test_a_footprint_publisher_listed_before_its_node_is_known_is_asked_about_again() -> None:
    """DDS can list an endpoint before the ROS node it belongs to is known (its node is then
    _NODE_NAMESPACE_UNKNOWN_): a robot seen that way first was never followed (the answer was kept while the
    count of publishers stayed the same)."""
    from fastep_ros.robots import RobotFollower
    graph = _GraphStub()
    follower = RobotFollower(graph, 0.5, 0.0, 3.0, 1.0, lambda: 0.0, lambda: None)   # type: ignore[arg-type]  # a stub
    graph.topics = [('/r2/footprint', [FOOTPRINT]), ('/r2/odom', ['nav_msgs/msg/Odometry'])]
    graph.publishers = {'/r2/footprint': [('_NODE_NAME_UNKNOWN_', '_NODE_NAMESPACE_UNKNOWN_')],
                        '/r2/odom': [('plant', '/r2')]}
    follower.discover()
    assert not follower.fleet.robots['/r2'].announced and '/r2/odom' not in graph.subscribed
    graph.publishers['/r2/footprint'] = [('planner', '/r2')]   # the same one publisher, its node now known
    follower.discover()
    assert follower.fleet.robots['/r2'].announced and '/r2/odom' in graph.subscribed


def test_one_look_at_the_graph_serves_the_planners_of_a_process(context: Any) -> None:
    """Planners in one process (a graph layout) share a look at the graph's topics for GRAPH_SHARED_FOR, and see a
    topic that appeared once it is over."""
    import rclpy
    from std_msgs.msg import Float64

    from fastep_ros.robots import GRAPH_SHARED_FOR, graph_topics
    a = rclpy.create_node('graph_a', context=context)
    b = rclpy.create_node('graph_b', context=context)
    asked: list[str] = []
    for node in (a, b):
        def counted(ask: Any = node.get_topic_names_and_types, name: str = node.get_name()) -> Any:
            asked.append(name)
            return ask()
        node.get_topic_names_and_types = counted  # type: ignore[method-assign]  # counts the looks
    try:
        first = graph_topics(a)
        assert graph_topics(b) is first and asked == ['graph_a']
        a.create_publisher(Float64, '/shared_look_topic', 1)
        time.sleep(GRAPH_SHARED_FOR + 0.05)
        assert '/shared_look_topic' in dict(graph_topics(b)) and asked == ['graph_a', 'graph_b']
    finally:
        a.destroy_node()
        b.destroy_node()


def test_known_movers_gone_quiet_are_kept_where_last_seen_their_reach_widening(world: World) -> None:
    """Issue "Faults", item 2: /movers stops (the map node stalled): each known mover stays where it was last seen,
    a disc of every place it can have reached at its last speed since; it was dropped after odom_timeout."""
    from visualization_msgs.msg import MarkerArray

    from fastep_core.planning.others import OtherRobot
    from msg_tools import interface
    planner = world.planner
    pub = world.node('map', '/').create_publisher(MarkerArray, interface.MOVERS, interface.RELIABLE)
    told_at = planner.get_clock().now()
    pub.publish(convert.movers_to_marker_array([OtherRobot('mover 0', (5.0, 5.0), (1.0, 0.0), 0.4, mover=True)],
                                               told_at.to_msg()))
    world.spin_until(lambda: planner.inputs.known_movers != [], 20.0, '/movers')
    told = told_at.nanoseconds * 1e-9
    [fresh] = planner.inputs.other_robots(told + 0.2)   # predicted along its velocity (max_extrapolation 0.25 s)
    assert fresh.position == pytest.approx((5.2, 5.0)) and fresh.velocity == (1.0, 0.0) and fresh.radius == 0.4
    later = planner.inputs.movers_received + 30.0
    [stale] = planner.inputs.other_robots(later)
    assert stale.mover and stale.position == (5.0, 5.0) and stale.velocity == (0.0, 0.0)
    assert stale.radius == pytest.approx(0.4 + 1.0 * (later - told))
    assert planner.inputs.stale_inputs(later) == [('/movers', pytest.approx(30.0))]
