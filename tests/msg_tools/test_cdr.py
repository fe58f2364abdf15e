"""msg_tools.cdr: the struct readers of the high-rate types agree with rclpy's deserialisation."""

from __future__ import annotations

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
