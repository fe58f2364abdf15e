"""msg_tools.mcap_writer: what it writes reads back (our reader, the mcap library's) with the ROS 2 profile, and
what it refuses is one line."""

from __future__ import annotations

from pathlib import Path

import pytest
from mcap.reader import make_reader
from std_msgs.msg import Float64

from msg_tools.errors import RecordingError
from msg_tools.mcap_io import open_recording
from msg_tools.mcap_writer import McapWriter
from msg_tools.ros2_profile import qos_dict, qos_from_dicts


def test_writer_round_trip_and_qos(tmp_path: Path) -> None:
    path = tmp_path / 'w.mcap'
    with McapWriter(path, compression='lz4') as writer:
        writer.add_channel('/map', 'nav_msgs/msg/OccupancyGrid', [qos_dict(depth=1, transient_local=True)])
        writer.write('/x', Float64(data=1.5), 3)
        writer.write('/x', Float64(data=2.5), 5, 4)
        with pytest.raises(RecordingError, match='already recorded'):
            writer.add_channel('/x', 'std_msgs/msg/String')
    recording = open_recording(path)
    assert [(m.log_time, m.message.data) for m in recording.messages()] == [(3, 1.5), (5, 2.5)]
    assert [r.publish_time for r in recording.raw_messages()] == [3, 4]
    latched = qos_from_dicts(recording.topics['/map'].qos)
    plain_qos = qos_from_dicts(recording.topics['/x'].qos)
    assert (latched.durability.name, latched.depth) == ('TRANSIENT_LOCAL', 1)
    assert (plain_qos.durability.name, plain_qos.reliability.name, plain_qos.depth) == ('VOLATILE', 'RELIABLE', 10)
    # rosbag2 metadata version <= 8 wrote numbers; an unknown history keeps the default depth.
    old = qos_from_dicts([{'history': 3, 'depth': 0, 'reliability': 1, 'durability': 1}])
    assert (old.durability.name, old.reliability.name, old.depth) == ('TRANSIENT_LOCAL', 'RELIABLE', 10)


def test_the_header_says_ros2_and_bytes_need_their_type(tmp_path: Path) -> None:
    path = tmp_path / 'raw.mcap'
    with McapWriter(path, compression='none') as writer:
        with pytest.raises(RecordingError, match='raw bytes need a type_name'):
            writer.write('/y', b'\x00\x01\x00\x00', 1)
        writer.write('/y', b'\x00\x01\x00\x00\x00\x00\x00\x00\x00\x00\xf8\x3f', 1, type_name='std_msgs/msg/Float64')
    with open(path, 'rb') as f:
        reader = make_reader(f)
        header = reader.get_header()
        assert header.profile == 'ros2'
        [(schema, channel, message)] = list(reader.iter_messages())
        assert (schema.name, schema.encoding, channel.message_encoding) == ('std_msgs/msg/Float64', 'ros2msg', 'cdr')
    assert [m.message.data for m in open_recording(path).messages()] == [1.5]
    with pytest.raises(RecordingError, match='compression must be one of'):
        McapWriter(tmp_path / 'bad.mcap', compression='gzip')
