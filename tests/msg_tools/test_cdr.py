"""msg_tools.cdr: the struct readers of the high-rate types agree with rclpy's deserialisation."""

from __future__ import annotations

from typing import Any

import pytest

from msg_tools import cdr


@pytest.mark.parametrize('frame', ['', 'm', 'map', 'odom', 'world_frame'])
@pytest.mark.parametrize('child', ['', 'r1/base_link', 'ab'])
def test_fast_cdr_readers_agree_with_rclpy(frame: str, child: str) -> None:
    """The struct readers of Odometry / Twist / Float64 give rclpy's values (alignment after strings
    of every length)."""
    from rclpy.serialization import serialize_message
    from std_msgs.msg import Float64

    from msg_tools import convert
    odom = convert.state_to_odometry((1.25, -3.5, 0.7, 0.1), convert.seconds_to_stamp(12.5), frame_id=frame,
                                     child_frame_id=child, linear=(0.3, -0.2), angular=0.9)
    odom.pose.covariance[0] = 7.0
    odom.twist.covariance[35] = -1.0
    q = odom.pose.pose.orientation
    data = serialize_message(odom)
    assert cdr.header_stamp(data) == (12, 500_000_000)
    assert cdr.odometry_fields(data) == (1.25, -3.5, q.x, q.y, q.z, q.w, 0.3, -0.2, 0.9)
    twist = convert.command_to_twist((0.5, -0.25))
    twist.angular.z = 0.125
    assert cdr.twist_fields(serialize_message(twist)) == (0.5, -0.25, 0.125)
    assert cdr.float64_field(serialize_message(Float64(data=-2.75))) == -2.75
    assert cdr.twist_fields(b'\x00\x00\x00\x00' + bytes(48)) is None  # big-endian CDR: left to rclpy


def test_a_cut_off_odometry_is_a_cdr_error() -> None:
    from rclpy.serialization import serialize_message

    from msg_tools import convert
    data = serialize_message(convert.state_to_odometry((1.0, 2.0)))
    with pytest.raises(cdr.CdrError, match='cut off'):
        cdr.odometry_fields(data[:-8])


@pytest.mark.parametrize('yaw', [0.0, 0.3, -2.9, 3.141592653589793])
def test_odometry_bytes_read_as_the_message_would_be(yaw: float) -> None:
    """A planner reads the other robots' odometry from its bytes (fastep_ros.robots): the same position,
    map-frame velocity and stamp, to the last bit, as from the deserialised message; bad bytes are one error."""
    from rclpy.serialization import serialize_message

    from fastep_ros.robots import odometry_reading
    from msg_tools import convert
    odom = convert.state_to_odometry((1.25, -3.5, yaw), convert.seconds_to_stamp(16.45), frame_id='r2/odom',
                                     child_frame_id='r2/base_link', linear=(0.3, 0.0), angular=0.2)
    assert odometry_reading(serialize_message(odom)) == odometry_reading(odom)
    odom.pose.pose.position.x = float('nan')
    with pytest.raises(ValueError, match='odometry position is not finite'):
        odometry_reading(serialize_message(odom))
    with pytest.raises(cdr.CdrError):
        odometry_reading(serialize_message(odom)[:40])


@pytest.mark.parametrize('frame', ['', 'm', 'map', 'r12/odom'])
@pytest.mark.parametrize('child', ['', 'r1/base_link', 'ab'])
def test_the_writers_make_the_message_rclpy_reads(frame: str, child: str) -> None:
    """Bytes a node publishes as they are decode with rclpy to the message convert builds (padding after frame
    names of every length), and the readers give them back."""
    from geometry_msgs.msg import Twist, TwistStamped
    from nav_msgs.msg import Odometry
    from rclpy.serialization import deserialize_message
    from rosgraph_msgs.msg import Clock
    from std_msgs.msg import Float64

    from msg_tools import convert
    stamp = convert.seconds_to_stamp(16.45)
    assert cdr.stamp_parts(16.45) == (stamp.sec, stamp.nanosec)
    odom = convert.state_to_odometry((1.25, -3.5, 0.7), stamp, frame_id=frame, child_frame_id=child,
                                     linear=(0.3, -0.2), angular=0.9)
    q = odom.pose.pose.orientation
    data = cdr.odometry_cdr((stamp.sec, stamp.nanosec), frame, child, (1.25, -3.5), (q.x, q.y, q.z, q.w),
                            (0.3, -0.2), 0.9)
    assert deserialize_message(data, Odometry) == odom
    assert cdr.header_frame_id(data) == frame
    twist = convert.command_to_twist((0.5, -0.25))
    twist.angular.z = 0.125
    assert deserialize_message(cdr.twist_cdr((0.5, -0.25), 0.125), Twist) == twist
    stamped = TwistStamped(twist=twist)
    stamped.header.stamp, stamped.header.frame_id = stamp, frame
    data = cdr.twist_stamped_cdr((stamp.sec, stamp.nanosec), frame, (0.5, -0.25), 0.125)
    assert deserialize_message(data, TwistStamped) == stamped
    assert cdr.twist_stamped_fields(data) == (0.5, -0.25, 0.125)
    assert cdr.header_stamp(data) == (16, 450_000_000)
    assert deserialize_message(cdr.float64_cdr(-2.75), Float64) == Float64(data=-2.75)
    assert deserialize_message(cdr.clock_cdr((3, 5)), Clock) == Clock(clock=convert.seconds_to_stamp(3.000000005))


def test_cut_off_headers_are_cdr_errors() -> None:
    data = cdr.twist_stamped_cdr((1, 0), 'r1/base_link', (1.0, 0.0), 0.0)
    for cut in (10, 20):
        with pytest.raises(cdr.CdrError, match='cut off'):
            cdr.header_frame_id(data[:cut])
    with pytest.raises(cdr.CdrError, match='cut off'):
        cdr.twist_stamped_fields(data[:-8])



FRAMES = ['', 'map', 'a_longer_frame']   # padded differently after them: to 4 before a length, to 8 before doubles
PATHS = {'empty': [], 'one point': [(1.25, -3.5)],
         'several points': [(0.0, 0.0), (1.5, 2.25), (-3.0, 1e-9), (7.125, 1e300), (-0.0, -2.5), (18.0, 10.5)]}
STATUSES = {
    'no values': (2, '/r1', 'failed', 'planner', []),
    'planner values': (0, '/r12', 'kinematic', '', [('reason', ''), ('activations', '3'), ('waypoint', '1.5,2'),
                                                    ('control_ms', '1.234 / 5.678 / 9.012')]),
    'unicode': (1, '/r1', 'stale', '', [('reason', 'odometry stale: Δt 0.25 s ≥ max_extrapolation'),
                                        ('robot', 'ロボット'), ('emoji', '🤖')]),
    'empty strings': (3, '', '', '', [('', ''), ('k', ''), ('kv', 'x')]),
}


def _header(msg: Any) -> tuple[int, int, str]:
    return msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id


def _pose(msg: Any) -> tuple[str, ...]:
    """A PoseStamped's numbers, as repr (NaN and -0.0 compare as themselves)."""
    p, q = msg.pose.position, msg.pose.orientation
    return tuple(repr(v) for v in (p.x, p.y, p.z, q.x, q.y, q.z, q.w))


@pytest.mark.parametrize('frame', FRAMES)
@pytest.mark.parametrize('points', PATHS.values(), ids=PATHS.keys())
def test_path_and_pose_bytes_decode_to_convert_s_messages(frame: str, points: list[tuple[float, float]]) -> None:
    """The waypoint and plan a planner publishes as bytes decode with rclpy to the messages convert builds, field by
    field: the path's header, and each pose's header (the path's stamp and frame), position and orientation."""
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path
    from rclpy.serialization import deserialize_message

    from msg_tools import convert
    stamp = convert.seconds_to_stamp(16.45)
    parts = (stamp.sec, stamp.nanosec)
    path = deserialize_message(cdr.path_cdr(parts, frame, points), Path)
    expected = convert.waypoints_to_path(points, stamp, frame)
    assert _header(path) == _header(expected) == (16, 450_000_000, frame)
    assert len(path.poses) == len(expected.poses) == len(points)
    for ours, theirs in zip(path.poses, expected.poses):
        assert _header(ours) == _header(theirs) == _header(expected)
        assert _pose(ours) == _pose(theirs)
    for point in [*points, (float('nan'), 2.0)]:
        pose = deserialize_message(cdr.pose_stamped_cdr(parts, frame, point), PoseStamped)
        expected_pose = convert.point_to_pose_stamped(point, stamp, frame)
        assert _header(pose) == _header(expected_pose) and _pose(pose) == _pose(expected_pose)


@pytest.mark.parametrize('status', STATUSES.values(), ids=STATUSES.keys())
def test_status_bytes_decode_to_make_status_s_message(status: tuple[int, str, str, str, list[tuple[str, str]]]) -> None:
    """A DiagnosticStatus written as bytes decodes to make_status's message, field by field (strings of every length
    mod 4, UTF-8 of several bytes a character, an empty one, none at all)."""
    from diagnostic_msgs.msg import DiagnosticStatus
    from rclpy.serialization import deserialize_message

    from msg_tools import convert
    level, name, message, hardware_id, values = status
    ours = deserialize_message(cdr.diagnostic_status_cdr(level, name, message, hardware_id, values), DiagnosticStatus)
    theirs = convert.make_status(name, message, bytes([level]), dict(values), hardware_id)
    assert (ours.level, ours.name, ours.message, ours.hardware_id) == \
        (theirs.level, theirs.name, theirs.message, theirs.hardware_id) == (bytes([level]), name, message, hardware_id)
    assert [(kv.key, kv.value) for kv in ours.values] == [(kv.key, kv.value) for kv in theirs.values] == values


def test_status_values_are_make_status_s_texts() -> None:
    """status_values, which a planner writes as bytes, gives the key/value texts of make_status's message."""
    import numpy as np

    from msg_tools import convert
    values = {'reason': 'stepping around', 'activations': 3, 'waypoint': np.array([1.5, 2.0]), 'goal': None,
              'cost': 0.1234567, 'goal_xy': (1.0, 2.5), 4: 'int key'}
    pairs = convert.status_values(values)
    assert pairs == [('reason', 'stepping around'), ('activations', '3'), ('waypoint', '1.5,2'), ('goal', ''),
                     ('cost', '0.123457'), ('goal_xy', '1,2.5'), ('4', 'int key')]
    assert [(kv.key, kv.value) for kv in convert.make_status('/r1', 'avoiding', 'ok', values).values] == pairs
    assert convert.status_values(None) == []


def test_a_wall_clock_time_in_a_status_keeps_its_milliseconds() -> None:
    """A planner on wall time says `t` and `since` as seconds since 1970: at six significant digits they moved in
    steps of 10,000 s, and fastep-launch --no-clock timed every run 0.0 s."""
    from msg_tools import convert
    start, end = 1795880005.4586, 1795880068.3191
    pairs = dict(convert.status_values({'t': end, 'since': start, 'small': 12.3456789, 'huge': 3e15}))
    assert float(pairs['t']) - float(pairs['since']) == pytest.approx(end - start, abs=1e-3)
    assert pairs['small'] == '12.3457' and pairs['huge'] == '3e+15'


@pytest.mark.parametrize('frame', FRAMES)
def test_our_bytes_and_rclpy_s_decode_alike(frame: str) -> None:
    """rclpy's own serialisation of convert's message and our bytes decode to equal messages (the bytes themselves
    may differ in their padding, which rclpy leaves as it finds it), and have the same length."""
    from diagnostic_msgs.msg import DiagnosticStatus
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path
    from rclpy.serialization import deserialize_message, serialize_message

    from msg_tools import convert
    stamp = convert.seconds_to_stamp(1234.000000001)
    parts = (stamp.sec, stamp.nanosec)
    points = PATHS['several points']
    values = [*STATUSES['planner values'][4], ('robot', 'ロボット'), ('emoji', '🤖')]   # keys once each (a dict)
    cases = [
        (convert.point_to_pose_stamped(points[1], stamp, frame), cdr.pose_stamped_cdr(parts, frame, points[1])),
        (convert.waypoints_to_path(points, stamp, frame), cdr.path_cdr(parts, frame, points)),
        (convert.waypoints_to_path([], stamp, frame), cdr.path_cdr(parts, frame, [])),
        (convert.make_status(frame, 'avoiding', 'warn', dict(values), frame),
         cdr.diagnostic_status_cdr(1, frame, 'avoiding', frame, values)),
    ]
    for msg, data in cases:
        kind = type(msg)
        assert kind in (PoseStamped, Path, DiagnosticStatus)
        theirs = serialize_message(msg)
        assert deserialize_message(data, kind) == deserialize_message(theirs, kind) == msg
        assert len(data) == len(theirs) and data[:4] == theirs[:4]
