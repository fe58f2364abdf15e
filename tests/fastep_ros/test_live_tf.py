"""REP-105 frames on the nodes (fastep_ros.live_tf and the frame hooks of the plant and the planner), built in this
process with their callbacks called directly."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter

from fastep_ros.live_tf import TfBroadcaster
from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from fastep_testing.published import keep_published
from msg_tools import convert, frames

# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(cls: type, context: Any, namespace: str = '', **params: Any) -> Any:
    return cls(context=context, namespace=namespace,
               parameter_overrides=[Parameter(k, value=v) for k, v in {**SYNCHRONOUS, **params}.items()])


def odometry(x: float, y: float, yaw: float = 0.0, frame: str = 'r1/odom') -> Odometry:
    msg = convert.state_to_odometry([x, y, yaw, yaw], frame_id=frame, child_frame_id='r1/base_link')
    return msg


def test_plant_odometry_is_odom_to_base_link_in_its_namespace(context: Any) -> None:
    node = make(PlantNode, context, '/r1', start=[1.0, 2.0])
    seen: list[Odometry] = []
    keep_published(node.odom_pub, seen.append)
    try:
        node.advance(1.0)
        node.publish()
        assert (seen[-1].header.frame_id, seen[-1].child_frame_id) == ('r1/odom', 'r1/base_link')
        assert node.tf.static == [] or node.tf.static[0].child_frame_id == 'r1/odom'
    finally:
        node.destroy_node()


def test_without_tf2_msgs_a_node_says_once_that_it_publishes_no_tf(context: Any,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    monkeypatch.setitem(sys.modules, 'tf2_msgs', None)   # not importable, as with the PyPI ROS wheels
    monkeypatch.setitem(sys.modules, 'tf2_msgs.msg', None)
    assert frames.tf_message_class() is None
    node = make(PlantNode, context, '/r1', start=[1.0, 2.0])
    try:
        lines: list[str] = []

        class Logger:
            def info(self, text: str) -> None:
                lines.append(text)

        node.get_logger = Logger  # type: ignore[method-assign]  # keep what is said
        broadcaster = TfBroadcaster(node)
        assert not broadcaster.available and broadcaster.dynamic_pub is None
        for _ in range(3):
            broadcaster.send(frames.odometry_transforms(odometry(1.0, 2.0)))   # nothing, silently
        broadcaster.send_static([frames.static_map_to_odom('map', 'r1/odom')])
        assert len(lines) == 1 and lines[0].startswith('tf2_msgs is not installed: not publishing /tf')
        assert {p.topic_name for p in node.publishers}.isdisjoint({'/tf', '/tf_static'})
        assert not node.tf.available
    finally:
        node.destroy_node()


def test_with_a_tf_message_class_a_node_publishes_tf_and_latched_tf_static(context: Any) -> None:
    """Where tf2_msgs is importable: /tf volatile 100 deep, /tf_static transient-local holding every static
    transform. (A stand-in rosidl class with a `transforms` list: tf2_msgs is not installed here.)"""
    from rclpy.qos import DurabilityPolicy

    sent: dict[str, list[Any]] = {}

    class Stand:   # what TfBroadcaster needs of TFMessage: a class built with transforms=[...]
        def __init__(self, transforms: list[Any]) -> None:
            self.transforms = transforms

    node = make(PlantNode, context, '/r1', start=[1.0, 2.0])
    try:
        created: list[tuple[str, Any]] = []

        def publisher(cls: type, topic: str, qos: Any) -> Any:
            created.append((topic, qos))

            class Pub:
                def publish(self, msg: Any) -> None:
                    sent.setdefault(topic, []).append(msg)
            return Pub()

        node.create_publisher = publisher  # type: ignore[method-assign]  # record what would be created
        broadcaster = TfBroadcaster(node, lambda: Stand)
        assert broadcaster.available
        qos = dict(created)
        assert qos['/tf'].depth == 100 and qos['/tf'].durability == DurabilityPolicy.VOLATILE
        assert qos['/tf_static'].depth == 1 and qos['/tf_static'].durability == DurabilityPolicy.TRANSIENT_LOCAL
        broadcaster.send_static([frames.static_map_to_odom('map', 'r1/odom')])
        broadcaster.send_static([frames.static_map_to_odom('map', 'r2/odom')])
        assert [t.child_frame_id for t in sent['/tf_static'][-1].transforms] == ['r1/odom', 'r2/odom']
        broadcaster.send(frames.odometry_transforms(odometry(1.0, 2.0)))
        (tf,) = sent['/tf'][-1].transforms
        assert (tf.header.frame_id, tf.child_frame_id, tf.transform.translation.x) == ('r1/odom', 'r1/base_link', 1.0)
    finally:
        node.destroy_node()


def test_stamped_cmd_vel_of_a_root_namespace_tractor_trailer_is_in_base_link_without_a_slash(context: Any) -> None:
    """Finding: a tractor-trailer in the root namespace stamped its TwistStamped `/base_link`."""
    planner = make(PlannerNode, context, use_stamped_cmd_vel=True, model='tractor_trailer', robot_radius=0.6)
    sent: list[TwistStamped] = []
    keep_published(planner.cmd_pub, sent.append)
    try:
        planner.publish_command(np.array([0.5, -0.25]))
        assert sent[-1].header.frame_id == 'base_link'
    finally:
        planner.destroy_node()
    planner = make(PlannerNode, context, '/r1', use_stamped_cmd_vel=True)   # a point mass: body frame too
    keep_published(planner.cmd_pub, sent.append)
    try:
        planner.publish_command(np.array([0.5, -0.25]))
        assert sent[-1].header.frame_id == 'r1/base_link'
        assert (sent[-1].twist.linear.x, sent[-1].twist.linear.y) == (0.5, -0.25)   # heading 0: unchanged
    finally:
        planner.destroy_node()


def _planner(context: Any, **params: Any) -> PlannerNode:
    node = make(PlannerNode, context, '/r1', workspace=[0.0, 0.0, 20.0, 20.0], **params)
    node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
    node.on_goal(convert.point_to_pose_stamped((3.0, 12.0)))
    return node


@pytest.mark.parametrize('frame', ['odom', 'world', 'r2/odom', ''])
def test_planner_refuses_odometry_in_a_frame_that_is_neither_map_nor_its_odom(context: Any, frame: str) -> None:
    """Finding: odometry stamped `odom` (here not this robot's odom frame) was used as a map pose."""
    node = _planner(context)
    try:
        node.inputs.on_odom(odometry(1.0, 1.0, frame=frame))
        node.on_control()
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.WARN, 'stale')
        assert f'odometry rejected: frame {frame!r} is neither the map frame' in reason and "'r1/odom'" in reason
        assert np.all(node.last_command == 0.0)
        node.inputs.on_odom(odometry(1.0, 1.0, frame='r1/odom'))   # its own odom frame: taken (map -> odom identity)
        node.on_control()
        assert node.reports.status()[1] == 'kinematic' and np.any(node.last_command != 0.0)
        node.inputs.on_odom(odometry(1.0, 1.0, frame='map'))       # the map frame: taken as it is
        assert node.inputs.odom_problem == ''
    finally:
        node.destroy_node()


def test_planner_composes_odometry_with_map_to_odom_from_the_localization_pose(context: Any) -> None:
    """With localization_topic, the map pose is localization o inverse(odometry at its stamp) o odometry; the robot
    waits still until the first localization pose; a point mass's map-frame command is turned into base_link."""
    node = _planner(context, localization_topic='amcl_pose')
    sent: list[Any] = []
    keep_published(node.cmd_pub, sent.append)
    try:
        assert node.inputs.localization_topic == '/r1/amcl_pose'
        node.inputs.on_odom(odometry(1.0, 1.0))
        node.on_control()
        assert node.reports.status() == (DiagnosticStatus.WARN, 'waiting',
                                 'waiting for localization on /r1/amcl_pose (map -> r1/odom)')
        assert (sent[-1].linear.x, sent[-1].linear.y) == (0.0, 0.0)
        # AMCL: base_link is at (3, 2) in the map, heading +y (odometry said (1, 1), heading +x).
        pose = PoseWithCovarianceStamped()
        pose.header.frame_id = 'map'
        pose.pose.pose.position.x, pose.pose.pose.position.y = 3.0, 2.0
        pose.pose.pose.orientation = convert.yaw_to_quaternion(math.pi / 2)
        node.inputs.on_localization(pose)
        assert node.inputs.map_from_odom.transform == pytest.approx((4.0, 1.0, math.pi / 2))
        node.inputs.on_odom(odometry(1.0, 1.0))
        state, problem = node.inputs.state(node.now())
        assert problem == '' and state is not None and state[:2] == pytest.approx([3.0, 2.0], abs=1e-6)
        node.on_control()
        assert node.reports.status()[1] == 'kinematic'
        # The goal (3, 12) is straight ahead along the map's +y, which is base_link's +x.
        assert node.last_command[0] == pytest.approx(0.0, abs=1e-6) and node.last_command[1] > 0.0
        assert sent[-1].linear.x == pytest.approx(node.last_command[1]) and sent[-1].linear.y == pytest.approx(0.0)
        pose.header.frame_id = 'r1/odom'   # a localization pose must be a map pose
        node.inputs.on_localization(pose)
        assert node.inputs.map_from_odom.localizations == 1
    finally:
        node.destroy_node()


def test_planner_turns_a_tractor_trailers_headings_by_map_to_odom(context: Any) -> None:
    node = make(PlannerNode, context, '/r1', model='tractor_trailer', robot_radius=0.6, localization_topic='amcl_pose',
                workspace=[0.0, 0.0, 20.0, 20.0])
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        node.inputs.on_odom(odometry(2.0, 0.0, yaw=0.25))
        node.inputs.on_trailer(convert.trailer_pose([2.0, 0.0, 0.25, 0.5], 1.0, 0.0, None, 'r1/odom'))
        # map -> odom turns by +0.5
        node.inputs.map_from_odom.add_localization(node.inputs.odom_stamp, (5.0, 5.0, 0.25 + 0.5))
        state, problem = node.inputs.state(node.now())
        assert problem == '' and state is not None
        assert state == pytest.approx([5.0, 5.0, 0.75, 1.0], abs=1e-6)
    finally:
        node.destroy_node()


def test_recorder_tf_parameter_derives_records_the_graphs_or_leaves_tf_out(context: Any, tmp_path: Path) -> None:
    from fastep_ros.common import StartupError
    from fastep_ros.recorder import RecorderNode

    for mode, derives, graph in (('derive', True, False), ('graph', False, True), ('none', False, False)):
        node = make(RecorderNode, context, output=str(tmp_path / f'{mode}.mcap'), tf=mode)
        try:
            assert (node.tf_from_odometry is not None, node.wants('/tf'), node.wants('/tf_static')) == \
                (derives, graph, graph)
            assert node.wants('/r1/odom')
        finally:
            node.destroy_node()
    with pytest.raises(StartupError, match='parameter tf must be derive, graph or none'):
        make(RecorderNode, context, output=str(tmp_path / 'bad.mcap'), tf='tf2')


@pytest.mark.parametrize('yaw', [0.0, 0.3, -2.9, 3.141592653589793])
def test_own_odometry_from_bytes_is_what_the_message_gives(yaw: float) -> None:
    """A planner takes its own odometry as bytes: the same frame, stamp and pose to the last bit as the message;
    a position that is not finite, or bytes cut off, is one ValueError."""
    from rclpy.serialization import serialize_message

    odom = convert.state_to_odometry((1.25, -3.5, yaw), convert.seconds_to_stamp(16.45), frame_id='r2/odom',
                                     child_frame_id='r2/base_link', linear=(0.3, 0.0), angular=0.2)
    assert frames.stamped_pose(serialize_message(odom)) == frames.stamped_pose(odom)
    assert frames.stamped_pose(odom).frame_id == 'r2/odom' and frames.stamped_pose(odom).stamp == 16.45
    odom.pose.pose.position.y = float('inf')
    with pytest.raises(ValueError, match='position is not finite'):
        frames.stamped_pose(serialize_message(odom))
    with pytest.raises(ValueError, match='cut off'):
        frames.stamped_pose(serialize_message(odom)[:100])


def test_planner_takes_map_to_odom_from_tf_when_asked(context: Any) -> None:
    """map_to_odom_from_tf (issue "Commanded like Nav2", item 3): map -> odom as AMCL or slam_toolbox publish it
    on /tf; the robot holds still until it comes; a newer transform moves the map pose."""
    from builtin_interfaces.msg import Time as TimeMsg

    from msg_tools.frames import static_map_to_odom, transform_stamped
    node = _planner(context, map_to_odom_from_tf=True)
    try:
        node.inputs.on_odom(odometry(1.0, 1.0))
        state, problem = node.inputs.state(node.now())
        assert state is None and problem == 'waiting for localization on /tf (map -> r1/odom)'
        tf_message = frames.tf_message_class()
        assert tf_message is not None
        node.tf.take(tf_message(transforms=[static_map_to_odom('map', 'r1/odom')]))
        state, problem = node.inputs.state(node.now())
        assert problem == '' and state is not None and tuple(state[:2]) == (1.0, 1.0)   # the identity, exactly
        node.tf.take(tf_message(transforms=[transform_stamped('map', 'r1/odom', (2.0, 0.5, 0.0), TimeMsg())]))
        state, _ = node.inputs.state(node.now())
        assert state is not None and state[:2] == pytest.approx([3.0, 1.5])
    finally:
        node.destroy_node()
