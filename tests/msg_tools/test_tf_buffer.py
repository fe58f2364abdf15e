"""msg_tools.tf_buffer.TfBuffer: tf2's lookups at a time, in the plane (chains, static and dynamic edges,
interpolation, what is not available), and TfTree's lookups at the latest time kept."""

from __future__ import annotations

import math

import pytest

from msg_tools import convert, frames
from msg_tools.tf_buffer import TfBuffer, TfUnavailable


def tf(parent: str, child: str, pose: frames.Pose2D, stamp: float = 0.0) -> object:
    return frames.transform_stamped(parent, child, pose, convert.seconds_to_stamp(stamp))


def robot(moving_mount: bool = False) -> TfBuffer:
    """odom -> base_link on /tf at 1, 2, 3 s (1 m/s along x, turning 0.1 rad/s); base_link -> mast (static, 0.1 m
    ahead), mast -> laser (static, 0.05 m left, turned 0.5 rad), or mast -> laser on /tf (a turret)."""
    buffer = TfBuffer()
    buffer.add([tf('base_link', 'mast', (0.1, 0.0, 0.0))], static=True)
    if moving_mount:
        buffer.add([tf('mast', 'laser', (0.0, 0.05, 0.0), 1.0), tf('mast', 'laser', (0.0, 0.05, 1.0), 3.0)])
    else:
        buffer.add([tf('mast', 'laser', (0.0, 0.05, 0.5))], static=True)
    for t in (1.0, 2.0, 3.0):
        buffer.add([tf('odom', 'base_link', (t, 0.0, 0.1 * t), t)])
    return buffer


def test_a_static_chain_composes_at_any_time_without_the_robots_motion() -> None:
    buffer = robot()
    for stamp in (None, 0.5, 2.0, 100.0):   # static edges hold at every time; odom -> base_link is not on the path
        assert buffer.lookup_at('base_link', 'laser', stamp) == pytest.approx((0.1, 0.05, 0.5))
    assert buffer.lookup_at('laser', 'base_link', 2.0) == pytest.approx(frames.inverse((0.1, 0.05, 0.5)))
    assert buffer.lookup_at('laser', 'laser', 7.0) == frames.IDENTITY


def test_a_dynamic_edge_is_interpolated_at_the_stamp_and_the_newest_is_the_latest() -> None:
    buffer = robot()
    x, y, yaw = buffer.lookup_at('odom', 'base_link', 1.5)
    assert (x, y, yaw) == pytest.approx((1.5, 0.0, 0.15))
    laser = buffer.lookup_at('odom', 'laser', 2.5)
    assert laser == pytest.approx(frames.compose((2.5, 0.0, 0.25), (0.1, 0.05, 0.5)))
    assert buffer.lookup('odom', 'base_link') == pytest.approx((3.0, 0.0, 0.3))   # TfTree's: the newest
    assert buffer.lookup_at('odom', 'base_link', None) == pytest.approx((3.0, 0.0, 0.3))


def test_a_moving_mount_is_looked_up_at_the_scans_stamp() -> None:
    buffer = robot(moving_mount=True)
    assert buffer.lookup_at('base_link', 'laser', 2.0) == pytest.approx((0.1, 0.05, 0.5))
    assert buffer.lookup_at('base_link', 'laser', 3.0) == pytest.approx((0.1, 0.05, 1.0))


def test_yaw_is_interpolated_the_shorter_way_round() -> None:
    buffer = TfBuffer()
    buffer.add([tf('odom', 'base_link', (0.0, 0.0, 3.0), 1.0), tf('odom', 'base_link', (0.0, 0.0, -3.0), 2.0)])
    yaw = buffer.lookup_at('odom', 'base_link', 1.5)[2]
    assert abs(abs(yaw) - math.pi) < 1e-9


def test_outside_the_buffer_and_unknown_frames_are_not_available_saying_why() -> None:
    buffer = robot(moving_mount=True)
    with pytest.raises(TfUnavailable, match=r"'mast' -> 'laser' at 3.500 s is not yet available \(newest 3.000 s\)"):
        buffer.lookup_at('base_link', 'laser', 3.5)
    with pytest.raises(TfUnavailable, match='older than the buffer'):
        buffer.lookup_at('odom', 'base_link', 0.5)
    with pytest.raises(TfUnavailable, match="'base_laser' is on neither /tf nor /tf_static"):
        buffer.lookup_at('base_link', 'base_laser', 2.0)
    buffer.add([tf('world', 'map', (0.0, 0.0, 0.0))], static=True)
    with pytest.raises(TfUnavailable, match='two trees'):
        buffer.lookup_at('map', 'laser', 2.0)
    assert buffer.lookup('map', 'laser') is None   # TfTree's answer: none


def test_the_buffer_keeps_cache_time_seconds_of_each_dynamic_edge() -> None:
    buffer = TfBuffer(cache_time=2.0)
    for k in range(11):
        buffer.add([tf('odom', 'base_link', (float(k), 0.0, 0.0), float(k))])
    assert buffer.history['base_link'].stamps == [8.0, 9.0, 10.0]
    assert buffer.lookup_at('odom', 'base_link', 8.5)[0] == pytest.approx(8.5)
    with pytest.raises(TfUnavailable):
        buffer.lookup_at('odom', 'base_link', 7.0)
    buffer.add([tf('odom', 'base_link', (4.0, 0.0, 0.0), 9.5)])   # late, out of order: in its place
    assert buffer.lookup_at('odom', 'base_link', 9.25)[0] == pytest.approx(6.5)


def test_an_edge_moved_to_tf_static_holds_at_every_time_and_a_cycle_is_refused() -> None:
    buffer = robot()
    buffer.add([tf('odom', 'base_link', (5.0, 0.0, 0.0))], static=True)
    assert buffer.lookup_at('odom', 'base_link', 50.0) == pytest.approx((5.0, 0.0, 0.0))
    buffer.add([tf('laser', 'odom', (0.0, 0.0, 0.0), 4.0)])   # odom is laser's ancestor: left out
    assert buffer.lookup_at('odom', 'laser', 50.0) == pytest.approx((5.1, 0.05, 0.5))
