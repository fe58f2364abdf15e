"""What a neighbour's TF cannot do to msg_tools.tf_buffer.TfBuffer: grow it without bound, make an older transform
the newest, stamp one in the future for ever; and TFMessage bytes read without messages (msg_tools.tf_cdr)."""

from __future__ import annotations

import math

import pytest

from msg_tools import cdr, convert, frames, tf_cdr
from msg_tools.tf_buffer import FRAMES_MAX, HISTORY_MAX, TfBuffer


def tf(parent: str, child: str, pose: frames.Pose2D, stamp: float = 0.0) -> object:
    return frames.transform_stamped(parent, child, pose, convert.seconds_to_stamp(stamp))


def raw(parent: str, child: str, pose: frames.Pose2D, stamp: float) -> cdr.Transform:
    """A transform as msg_tools.cdr.tf_message_cdr writes it."""
    q = convert.yaw_to_quaternion(pose[2])
    return (cdr.stamp_parts(stamp), parent, child, (pose[0], pose[1], 0.0), (q.x, q.y, q.z, q.w))


def flood(count: int, stamp: float, *real: cdr.Transform) -> bytes:
    """A TFMessage of `count` clutter frames, the `real` transforms among them (the first at the start, the others
    in the middle and at the end)."""
    clutter = [raw('clutter', f'clutter_{k}', (float(k), 0.0, 0.0), stamp) for k in range(count - len(real))]
    for i, transform in enumerate(real):
        clutter.insert((len(clutter) * i) // max(len(real) - 1, 1), transform)
    return cdr.tf_message_cdr(clutter)


def test_a_flood_of_new_frames_keeps_the_bound_and_the_frames_lookups_use() -> None:
    buffer = TfBuffer()
    buffer.add([tf('map', 'odom', (1.0, 2.0, 0.0), 1.0)], now=1.0)
    buffer.add([tf('odom', 'base_link', (0.5, 0.0, 0.0), 1.0)], now=1.0)
    buffer.add([tf('base_link', 'laser', (0.1, 0.0, 0.0))], static=True, now=1.0)
    assert buffer.lookup('map', 'laser') == pytest.approx((1.6, 2.0, 0.0))   # the frames a node looks up
    for k in range(20):   # 20 messages of 1000 new frames each, stamped later than every kept frame
        buffer.add([tf('clutter', f'c{k}_{i}', (0.0, 0.0, 0.0), 2.0 + k) for i in range(1000)], now=2.0 + k)
        assert len(buffer.parents) <= FRAMES_MAX
    assert buffer.dropped == 20 * 1000 + 3 - FRAMES_MAX
    assert buffer.lookup('map', 'laser') == pytest.approx((1.6, 2.0, 0.0))   # never dropped: looked up
    assert len(buffer.history) <= FRAMES_MAX and len(buffer.updated) == len(buffer.parents)


def test_an_edge_keeps_at_most_history_max_transforms() -> None:
    buffer = TfBuffer()
    for k in range(3 * HISTORY_MAX):   # 1 kHz: 1.5 s, within the 10 s of cache_time
        buffer.add([tf('odom', 'base_link', (k * 1e-3, 0.0, 0.0), 1.0 + k * 1e-3)])
    stamps = buffer.history['base_link'].stamps
    assert len(stamps) == HISTORY_MAX and stamps[-1] == pytest.approx(1.0 + (3 * HISTORY_MAX - 1) * 1e-3)
    newest = buffer.lookup('odom', 'base_link')
    assert newest is not None and newest[0] == pytest.approx((3 * HISTORY_MAX - 1) * 1e-3)


def test_an_older_stamp_never_replaces_a_newer_not_even_naming_another_parent() -> None:
    buffer = TfBuffer()
    buffer.add([tf('map', 'odom', (2.0, 0.0, 0.0), 5.0)], now=5.0)
    buffer.add([tf('map', 'odom', (9.0, 9.0, 0.0), 3.0)], now=5.1)     # late: history, not the newest
    assert buffer.lookup('map', 'odom') == pytest.approx((2.0, 0.0, 0.0))
    buffer.add([tf('world', 'odom', (7.0, 7.0, 0.0), 4.0)], now=5.2)   # another parent, older
    assert buffer.lookup('map', 'odom') == pytest.approx((2.0, 0.0, 0.0)) and buffer.refused_older == 1
    assert buffer.lookup('world', 'odom') is None
    buffer.add([tf('world', 'odom', (7.0, 7.0, 0.0), 6.0)], now=6.0)   # newer: re-parented, as tf2 does
    assert buffer.lookup('world', 'odom') == pytest.approx((7.0, 7.0, 0.0))


def test_stamps_against_the_clock_unset_ages_from_arrival_far_ahead_refused_a_clock_gone_back_starts_afresh() -> None:
    buffer = TfBuffer()
    buffer.add([tf('map', 'odom', (1.0, 0.0, 0.0))], now=12.5, ahead=2.0)   # unset stamp: ages from its arrival
    assert buffer.lookup_stamped('map', 'odom') == ((1.0, 0.0, 0.0), 12.5)
    buffer.add([tf('map', 'odom', (5.0, 5.0, 0.0), 1e6)], now=13.0, ahead=2.0)   # kept, it would win for ever
    assert buffer.refused_ahead == 1 and buffer.lookup('map', 'odom') == pytest.approx((1.0, 0.0, 0.0))
    buffer.add([tf('map', 'odom', (2.0, 0.0, 0.0), 14.5)], now=13.0, ahead=2.0)   # within `ahead`: post-dated
    assert buffer.lookup_stamped('map', 'odom') == ((2.0, 0.0, 0.0), 14.5)
    buffer.add([tf('map', 'odom', (3.0, 0.0, 0.0), 0.5)], now=0.5, ahead=2.0)   # a restarted clock
    assert buffer.lookup_stamped('map', 'odom') == ((3.0, 0.0, 0.0), 0.5)
    assert buffer.history['odom'].stamps == [0.5]


def test_lookup_stamped_holds_at_the_oldest_dynamic_edge_and_static_edges_never_age() -> None:
    buffer = TfBuffer()
    buffer.add([tf('map', 'odom', (0.0, 0.0, 0.0))], static=True)
    buffer.add([tf('odom', 'base_link', (1.0, 0.0, 0.0), 3.0), tf('base_link', 'turret', (0.1, 0.0, 0.0), 2.0)])
    assert buffer.lookup_stamped('map', 'odom') == ((0.0, 0.0, 0.0), math.inf)
    turret, in_base = buffer.lookup_stamped('map', 'turret'), buffer.lookup_stamped('base_link', 'turret')
    assert turret is not None and turret[0] == pytest.approx((1.1, 0.0, 0.0)) and turret[1] == 2.0
    assert in_base is not None and in_base[1] == 2.0   # odom -> base_link is not between them
    assert buffer.lookup_stamped('map', 'nowhere') is None


def test_tf_cdr_reads_what_rclpy_reads() -> None:
    from geometry_msgs.msg import TransformStamped
    from rclpy.serialization import serialize_message
    from tf2_msgs.msg import TFMessage
    transforms = []
    for parent, child, x in (('map', 'r1/odom', 1.5), ('/r1/odom', 'r1/base_link', -2.25), ('a', 'bcdefgh', 3.0)):
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = parent, child
        t.header.stamp = convert.seconds_to_stamp(7.25)
        t.transform.translation.x, t.transform.translation.z = x, 0.5
        t.transform.rotation = convert.yaw_to_quaternion(0.3)
        transforms.append(t)
    data = serialize_message(TFMessage(transforms=transforms))
    edges = tf_cdr.read_all(data)
    assert edges is not None and [(e[0], e[1], e[2], e[3][0], e[3][2]) for e in edges] == [
        ('map', 'r1/odom', 7.25, 1.5, 0.5), ('/r1/odom', 'r1/base_link', 7.25, -2.25, 0.5),
        ('a', 'bcdefgh', 7.25, 3.0, 0.5)]
    assert tf_cdr.read_children(data, ['r1/base_link', 'bcdefgh', 'map']) == {'r1/base_link': edges[1],
                                                                             'bcdefgh': edges[2]}
    assert tf_cdr.read_children(data, ['r1/odom']) == {'r1/odom': edges[0]}   # the child, not the next parent
    with pytest.raises(ValueError, match='cut off after 1 of 3 transforms'):
        tf_cdr.read_all(data[:110])
    assert tf_cdr.transform_count(b'\x00\x00\x00\x00' + data[4:]) is None   # big-endian: rclpy's to read


def test_a_child_edge_is_found_behind_any_number_of_transforms_whose_parent_is_that_frame() -> None:
    """map -> odom first, then many odom -> X: each X's header names odom as CDR names the child; all are passed
    over. Also a child whose first double reads like a string's length and its first character."""
    import struct

    from geometry_msgs.msg import TransformStamped
    from rclpy.serialization import serialize_message
    from tf2_msgs.msg import TFMessage
    odd = struct.unpack('<d', b'\x05\x00\x00\x00\x41\x00\x43\x3f')[0]
    for parent in ('m', 'ma', 'map', 'mapp', 'mappp', 'a/map', 'ab/map', 'abc/map'):   # every alignment
        for x, after in ((1.25, 2000), (odd, 3)):
            transforms = []
            for p, c in [(parent, 'odom'), *(('odom', f'r{i}/base_link') for i in range(after))]:
                t = TransformStamped()
                t.header.frame_id, t.child_frame_id = p, c
                t.header.stamp = convert.seconds_to_stamp(3.5)
                t.transform.rotation.w = 1.0
                transforms.append(t)
            transforms[0].transform.translation.x = x
            found = tf_cdr.read_children(serialize_message(TFMessage(transforms=transforms)), ['odom'])
            assert found is not None and found['odom'][:3] == (parent, 'odom', 3.5), (parent, found)
            assert found['odom'][3][0] == x


def test_a_message_read_in_part_takes_only_the_needed_frames_and_their_parents() -> None:
    buffer = TfBuffer()
    assert buffer.lookup('map', 'r1/base_link') is None   # asked for before any TF came
    data = flood(20_000, 3.0, raw('map', 'world', (1.0, 0.0, 0.0), 3.0), raw('world', 'r1/odom', (0.0, 1.0, 0.0), 3.0),
                 raw('r1/odom', 'r1/base_link', (0.5, 0.5, 0.0), 3.0))
    taken = buffer.add_cdr(data, now=3.0, whole=False)
    assert taken is not None and (taken.count, taken.read, taken.kept, taken.whole) == (20_000, 3, 3, False)
    assert set(taken.searched) == {'map', 'r1/base_link', 'r1/odom', 'world'}
    assert buffer.lookup('map', 'r1/base_link') == pytest.approx((1.5, 1.5, 0.0))
    assert sorted(buffer.parents) == ['r1/base_link', 'r1/odom', 'world']
    whole = buffer.add_cdr(flood(50, 4.0), now=4.0)
    assert whole is not None and (whole.read, whole.kept, whole.whole) == (50, 50, True) and len(buffer.parents) == 53
