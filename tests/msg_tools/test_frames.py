"""msg_tools.frames: planar pose algebra, map -> odom from localization, and TF in recordings (decoded with rosbags:
tf2_msgs has no rclpy class here)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rclpy.serialization import serialize_message
from rosbags.highlevel import AnyReader

from msg_tools import convert, frames, report, sim_cli
from msg_tools.mcap_io import open_recording


def test_frame_names_never_start_with_a_slash() -> None:
    assert frames.odom_frame('/r1') == 'r1/odom' and frames.base_frame('/r1') == 'r1/base_link'
    assert frames.odom_frame('/') == 'odom' and frames.base_frame('') == 'base_link'
    assert frames.trailer_frame('/fleet/r2') == 'fleet/r2/trailer_link'


def test_compose_and_inverse() -> None:
    rng = np.random.default_rng(3)
    for _ in range(50):
        a = (*rng.uniform(-10, 10, 2), rng.uniform(-math.pi, math.pi))
        b = (*rng.uniform(-10, 10, 2), rng.uniform(-math.pi, math.pi))
        assert frames.compose(a, frames.inverse(a)) == pytest.approx(frames.IDENTITY, abs=1e-9)
        assert frames.compose(frames.inverse(a), frames.compose(a, b)) == pytest.approx(b, abs=1e-9)
    # A quarter turn about the origin then a shift: (1, 0) in the child is (2, 4) in the parent.
    assert frames.compose((2.0, 3.0, math.pi / 2), (1.0, 0.0, 0.0))[:2] == pytest.approx((2.0, 4.0))


def test_state_in_frame_turns_the_point_and_every_heading_and_leaves_the_identity_exact() -> None:
    state = np.array([1.0, 2.0, 0.3, -0.2])
    assert frames.state_in_frame(frames.IDENTITY, state) is state
    moved = frames.state_in_frame((1.0, -1.0, math.pi / 2), state)
    assert moved == pytest.approx([1.0 - 2.0, -1.0 + 1.0, 0.3 + math.pi / 2, -0.2 + math.pi / 2])
    assert frames.state_in_frame((1.0, -1.0, 0.0), np.array([1.0, 2.0])) == pytest.approx([2.0, 1.0])


def test_body_velocity_is_the_velocity_seen_from_the_body() -> None:
    assert frames.body_velocity((0.0, 1.0), math.pi / 2) == pytest.approx((1.0, 0.0))
    assert frames.body_velocity((0.3, -0.4), 0.0) == (0.3, -0.4)   # heading 0 (a point mass): unchanged


def test_map_from_odom_uses_the_odometry_nearest_to_the_localization_stamp() -> None:
    m = frames.MapFromOdom(keep=3)
    m.add_localization(1.0, (5.0, 5.0, 0.0))   # before any odometry: waits for it
    assert m.transform is None and m.pending is not None
    m.add_odometry(1.0, (1.0, 0.0, 0.0))
    assert m.transform == pytest.approx((4.0, 5.0, 0.0))
    for t in (2.0, 3.0, 4.0):
        m.add_odometry(t, (t, 0.0, 0.0))
    assert m.history.stamps == (2.0, 3.0, 4.0)   # only `keep` kept
    m.add_localization(3.4, (10.0, 0.0, math.pi))   # nearest: the odometry at 3.0
    assert m.transform == pytest.approx((13.0, 0.0, math.pi))
    assert frames.compose(m.transform, (3.0, 0.0, 0.0)) == pytest.approx((10.0, 0.0, math.pi))
    m.add_odometry(0.5, (0.0, 0.0, 0.0))   # time went back: the old odometry is forgotten
    assert m.history.stamps == (0.5,) and m.localizations == 2


def test_tf_message_cdr_decodes_with_rosbags() -> None:
    from rosbags.typesys import Stores, get_typestore
    stamp = convert.seconds_to_stamp(12.5)
    transforms = [frames.transform_stamped('r1/odom', 'r1/base_link', (1.0, 2.0, 0.5), stamp),
                  frames.static_map_to_odom('map', 'r1/odom', stamp)]
    msg = get_typestore(Stores.ROS2_JAZZY).deserialize_cdr(frames.tf_message_cdr(transforms), frames.TF_TYPE)
    first, second = msg.transforms
    assert (first.header.frame_id, first.child_frame_id) == ('r1/odom', 'r1/base_link')
    assert (first.header.stamp.sec, first.header.stamp.nanosec) == (12, 500_000_000)
    assert (first.transform.translation.x, first.transform.translation.y) == (1.0, 2.0)
    assert first.transform.rotation.z == pytest.approx(math.sin(0.25))
    assert (second.header.frame_id, second.child_frame_id, second.transform.rotation.w) == ('map', 'r1/odom', 1.0)


def test_tf_from_odometry_gives_static_map_to_odom_once_and_tf_for_every_odometry() -> None:
    derive = frames.TfFromOdometry()
    odom = serialize_message(convert.state_to_odometry([1.0, 2.0], frame_id='r1/odom', child_frame_id='r1/base_link'))
    first = derive.take('/r1/odom', odom)
    assert [topic for topic, _ in first] == ['/tf_static', '/tf']
    assert [topic for topic, _ in derive.take('/r1/odom', odom)] == ['/tf']
    other = serialize_message(convert.state_to_odometry([1.0, 2.0], frame_id='r2/odom', child_frame_id='r2/base_link'))
    static = dict(derive.take('/r2/odom', other))['/tf_static']
    from rosbags.typesys import Stores, get_typestore
    decoded = get_typestore(Stores.ROS2_JAZZY).deserialize_cdr(static, frames.TF_TYPE)
    assert [t.child_frame_id for t in decoded.transforms] == ['r1/odom', 'r2/odom']   # one latched message: all
    in_map = serialize_message(convert.state_to_odometry([1.0, 2.0], frame_id='map'))
    assert [topic for topic, _ in frames.TfFromOdometry().take('/r3/odom', in_map)] == ['/tf']
    trailer = serialize_message(convert.trailer_pose([0.0, 0.0, 0.0, 0.0], 1.0, 0.0, None, 'r1/odom'))
    assert [topic for topic, _ in derive.take('/r1/trailer_pose', trailer)] == ['/tf']
    assert derive.take('/r1/cost', b'') == [] and derive.take('/r1/odom', b'\x00\x01') == []


def test_fastep_sim_recording_carries_tf_that_rosbags_decodes_and_fastep_report_reads(tmp_path: Path) -> None:
    out = tmp_path / 'application.mcap'
    assert sim_cli.main(['application', '--mcap', str(out)]) == 0   # tractor-trailers: trailer_link too
    with AnyReader([out]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types['/tf'] == types['/tf_static'] == frames.TF_TYPE
        statics: list[Any] = []
        dynamic: dict[tuple[str, str], list[Any]] = {}
        odom: dict[str, list[Any]] = {}
        for c, t, raw in reader.messages():
            if c.topic == '/tf_static':
                statics.extend(reader.deserialize(raw, c.msgtype).transforms)
            elif c.topic == '/tf':
                for tf in reader.deserialize(raw, c.msgtype).transforms:
                    dynamic.setdefault((tf.header.frame_id, tf.child_frame_id), []).append((t, tf))
            elif c.topic.endswith('/odom'):
                odom.setdefault(c.topic, []).append((t, reader.deserialize(raw, c.msgtype)))
    assert sorted((s.header.frame_id, s.child_frame_id) for s in statics) == [('map', 'r1/odom'), ('map', 'r2/odom')]
    assert sorted(dynamic) == [('r1/odom', 'r1/base_link'), ('r1/odom', 'r1/trailer_link'),
                               ('r2/odom', 'r2/base_link'), ('r2/odom', 'r2/trailer_link')]
    for robot in ('r1', 'r2'):
        poses = odom[f'/{robot}/odom']
        assert {(m.header.frame_id, m.child_frame_id) for _, m in poses} == {(f'{robot}/odom', f'{robot}/base_link')}
        tfs = dynamic[(f'{robot}/odom', f'{robot}/base_link')]
        assert len(tfs) == len(poses)
        for (t_odom, m), (t_tf, tf) in zip(poses, tfs):
            assert t_odom == t_tf
            assert (tf.transform.translation.x, tf.transform.translation.y) == (m.pose.pose.position.x,
                                                                              m.pose.pose.position.y)
            assert tf.transform.rotation.z == m.pose.pose.orientation.z
    # Our reader decodes TF with rosbags too, and the report ignores it.
    recording = open_recording(out)
    assert next(recording.messages(['/tf'])).message.transforms[0].child_frame_id in ('r1/base_link', 'r2/base_link')
    assert report.main([str(out), '--out', str(tmp_path / 'report')]) == 0


def test_the_live_diff_drive_bag_is_foxglove_ready() -> None:
    """bags/diff_drive_swap_live.mcap (bags/README.md): a live fastep-launch run of two diff-drive bases, both at
    their goals, odometry in odom frames, /tf and /tf_static that rosbags decodes."""
    path = Path(__file__).resolve().parents[2] / 'bags' / 'diff_drive_swap_live.mcap'
    assert path.stat().st_size < 2 * 1024 * 1024
    with AnyReader([path]) as reader:
        topics = {c.topic: c for c in reader.connections}
        assert topics['/tf'].msgtype == topics['/tf_static'].msgtype == frames.TF_TYPE
        tf = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages([topics['/tf_static'],
                                                                                    topics['/tf']])]
        odom = [reader.deserialize(raw, c.msgtype)
                for c, _, raw in reader.messages([topics['/r1/odom'], topics['/r2/odom']])]
    pairs = {(t.header.frame_id, t.child_frame_id) for m in tf for t in m.transforms}
    assert pairs == {('map', 'r1/odom'), ('map', 'r2/odom'), ('r1/odom', 'r1/base_link'), ('r2/odom', 'r2/base_link')}
    assert {(m.header.frame_id, m.child_frame_id) for m in odom} == {('r1/odom', 'r1/base_link'),
                                                                   ('r2/odom', 'r2/base_link')}
    recording = open_recording(path)
    assert recording.metadata['fastep']['model/r1'] == recording.metadata['fastep']['model/r2'] == 'diff_drive'
    statuses = {m.topic: m.message.message for m in recording.messages(['/r1/status', '/r2/status'])}
    assert statuses == {'/r1/status': 'arrived', '/r2/status': 'arrived'}


@pytest.mark.parametrize('frame, child', [('map', 'r1/base_link'), ('r2/odom', 'r2/base_link'), ('', ''),
                                          ('odom', 'abc')])
def test_tf_from_odometry_bytes_is_the_messages_tf(frame: str, child: str) -> None:
    """A recorder turns odometry into TF from its bytes (msg_tools.cdr): the transforms odometry_transforms gives of
    the message, decoded by rosbags; a static map -> odom once per odom frame; none of a position that is not
    finite or a quaternion of zero length."""
    from rclpy.serialization import serialize_message
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    odom = convert.state_to_odometry((1.25, -3.5, 0.7), convert.seconds_to_stamp(16.45), frame_id=frame,
                                     child_frame_id=child, linear=(0.3, 0.0), angular=0.2)
    odom.pose.pose.position.z = 0.25
    data = serialize_message(odom)
    fast = frames.TfFromOdometry()
    got = fast.take('/r1/odom', data)
    want = [(frames.TF, frames.tf_message_cdr(frames.odometry_transforms(odom)))]
    if frame and frame != 'map':
        want.insert(0, (frames.TF_STATIC, frames.tf_message_cdr(
            [frames.static_map_to_odom('map', frame, odom.header.stamp)])))
    assert [topic for topic, _ in got] == [topic for topic, _ in want]
    for (_, a), (_, b) in zip(got, want):
        assert str(store.deserialize_cdr(a, frames.TF_TYPE)) == str(store.deserialize_cdr(b, frames.TF_TYPE))
    assert [topic for topic, _ in fast.take('/r1/odom', data)] == [frames.TF]   # the static one once
    odom.pose.pose.position.x = float('nan')
    assert fast.take('/r1/odom', serialize_message(odom)) == []
    odom.pose.pose.position.x = 1.0
    odom.pose.pose.orientation.w = 0.0
    odom.pose.pose.orientation.z = 0.0
    assert fast.take('/r1/odom', serialize_message(odom)) == []
    assert fast.take('/r1/odom', data[:30]) == []   # cut off: nothing (the recording keeps the message)


def test_a_tf_tree_composes_along_the_tree_and_refuses_what_would_break_it() -> None:
    """frames.TfTree (the planner's goals in other frames): newest transform per edge, lookups both ways."""
    import math

    from builtin_interfaces.msg import Time

    from msg_tools.frames import TfTree, transform_stamped
    tree = TfTree()
    tree.add([transform_stamped('map', 'r1/odom', (1.0, 2.0, math.pi / 2), Time()),
              transform_stamped('r1/odom', 'r1/base_link', (1.0, 0.0, 0.0), Time()),
              transform_stamped('/map', 'r2/odom', (10.0, 0.0, 0.0), Time())])
    x, y, yaw = tree.lookup('map', 'r1/base_link')
    assert (x, y, yaw) == pytest.approx((1.0, 3.0, math.pi / 2))
    x, y, _ = tree.lookup('r2/odom', 'r1/base_link')
    assert (x, y) == pytest.approx((-9.0, 3.0))
    assert tree.lookup('map', 'elsewhere') is None and tree.lookup('map', 'map') == (0.0, 0.0, 0.0)
    tree.add([transform_stamped('r1/base_link', 'map', (0.0, 0.0, 0.0), Time()),     # a cycle: left out
              transform_stamped('map', 'bad', (math.nan, 0.0, 0.0), Time())])        # not finite: left out
    assert tree.lookup('map', 'r1/base_link') is not None and tree.lookup('map', 'bad') is None
    tree.add([transform_stamped('map', 'r1/odom', (0.0, 0.0, 0.0), Time())])          # the newest one counts
    assert tree.lookup('map', 'r1/base_link') == pytest.approx((1.0, 0.0, 0.0))
