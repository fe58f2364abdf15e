"""msg_tools.mcap_io and fastep-sim --mcap: ROS 2 profile MCAP that independent readers decode, and recovery.

A recording made by `fastep-sim --mcap` is decoded twice, with the `rosbags` library (its own CDR decoder and
.msg parser, fed only by the schemas in the file) and with the `mcap` reader + rclpy, and the decoded field
values must agree message for message. Cut-off copies of it must give their complete part or a one-line error.
"""

from __future__ import annotations

import array
import dataclasses
import math
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import SeekingReader
from rosbags.highlevel import AnyReader

from msg_tools import recover, sim_cli
from msg_tools.errors import NotMcapError, RecordingError, TruncatedRecordingError
from msg_tools.mcap_io import copy_recording, open_recording
from msg_tools.ros2_profile import message_definition, qos_dict

# One point mass and one tractor-trailer (so trailer_pose is there), a circle and a wall (both marker kinds).
MIXED = """\
name: mixed
workspace: [0, 0, 20, 20]
obstacles:
  - circle: {center: [10, 6], radius: 1.5}
  - segment: {start: [9, 13], end: [11, 15]}
robots:
  - name: r1
    model: point_mass
    start: [2, 6]
    goal: [18, 6.5]
    radius: 0.5
  - name: r2
    model: tractor_trailer
    start: [2, 14, 0.0, 0.0]
    goal: [18, 14]
    radius: 0.6
planner: {alpha1: 0.5, alpha2: 0.5, max_speed: 2.0}
"""

TYPES = {
    '/clock': 'rosgraph_msgs/msg/Clock', '/map': 'nav_msgs/msg/OccupancyGrid',
    '/obstacles': 'visualization_msgs/msg/MarkerArray',
    **{f'/{r}/{t}': ty for r in ('r1', 'r2') for t, ty in (
        ('odom', 'nav_msgs/msg/Odometry'), ('cmd_vel', 'geometry_msgs/msg/Twist'),
        ('goal_pose', 'geometry_msgs/msg/PoseStamped'), ('waypoint', 'geometry_msgs/msg/PoseStamped'),
        ('plan', 'nav_msgs/msg/Path'), ('cost', 'std_msgs/msg/Float64'),
        ('status', 'diagnostic_msgs/msg/DiagnosticStatus'), ('footprint', 'geometry_msgs/msg/PolygonStamped'))},
    '/r2/trailer_pose': 'geometry_msgs/msg/PoseStamped',
    '/tf': 'tf2_msgs/msg/TFMessage', '/tf_static': 'tf2_msgs/msg/TFMessage',
}


@pytest.fixture(scope='module')
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    folder = tmp_path_factory.mktemp('sim_mcap')
    scenario = folder / 'mixed.yaml'
    scenario.write_text(MIXED)
    out = folder / 'mixed.mcap'
    assert sim_cli.main([str(scenario), '--mcap', str(out), '--json', str(folder / 'mixed.json')]) == 0
    return {'path': out, 'folder': folder, 'json': folder / 'mixed.json'}


# ----------------------------------------------------------------------------------------------- helpers

def plain(value: Any) -> Any:
    """A decoded message (rclpy or rosbags) as nested dicts/lists of Python numbers and strings."""
    if hasattr(value, 'get_fields_and_field_types'):  # rclpy
        return {name: plain(getattr(value, name)) for name in value.get_fields_and_field_types()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):  # rosbags: skip constants (UPPER case)
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)
                if f.name != '__msgtype__' and not f.name.isupper()}
    if isinstance(value, bytes):
        return value[0] if len(value) == 1 else list(value)  # rclpy gives `byte` fields as bytes
    if isinstance(value, (list, tuple, np.ndarray, array.array)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def same(a: Any, b: Any, where: str = '') -> None:
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), where
        for key in a:
            same(a[key], b[key], f'{where}.{key}')
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f'{where}[{i}]')
    elif isinstance(a, float) and math.isnan(a):
        assert isinstance(b, float) and math.isnan(b), where
    else:
        assert a == b, f'{where}: {a!r} != {b!r}'


# ----------------------------------------------------------------------------------------------- schemas

def test_schema_text_is_msg_then_each_nested_type_once() -> None:
    text = message_definition('nav_msgs/msg/Odometry')
    lines = text.splitlines()
    assert lines[0].startswith('# This represents an estimate of a position and velocity')
    separators = [i for i, line in enumerate(lines) if set(line) == {'='}]
    assert separators and all(len(lines[i]) == 80 for i in separators)
    nested = [lines[i + 1] for i in separators]
    assert all(line.startswith('MSG: ') for line in nested)
    names = [line[5:] for line in nested]
    assert len(names) == len(set(names))
    assert {'std_msgs/Header', 'builtin_interfaces/Time', 'geometry_msgs/PoseWithCovariance',
            'geometry_msgs/Pose', 'geometry_msgs/Point', 'geometry_msgs/Quaternion',
            'geometry_msgs/TwistWithCovariance', 'geometry_msgs/Twist', 'geometry_msgs/Vector3'} == set(names)
    assert message_definition('nav_msgs/Odometry') == text
    with pytest.raises(RecordingError, match='not a ROS 2 message type'):
        message_definition('Odometry')
    with pytest.raises(RecordingError, match='no message definition'):
        message_definition('nav_msgs/msg/NoSuchType')


def test_file_has_the_ros2_profile_channels_and_summary(recorded: dict[str, Any]) -> None:
    with open(recorded['path'], 'rb') as f:
        reader = SeekingReader(f)
        assert reader.get_header().profile == 'ros2'
        summary = reader.get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count > 1000
    assert {c.compression for c in summary.chunk_indexes} == {'zstd'}
    topics = {}
    for channel in summary.channels.values():
        schema = summary.schemas[channel.schema_id]
        assert channel.message_encoding == 'cdr'
        assert schema.encoding == 'ros2msg'
        assert schema.data.decode() == message_definition(schema.name)
        topics[channel.topic] = schema.name
        durability = 'transient_local' if channel.topic in ('/map', '/obstacles', '/tf_static') or \
            channel.topic.endswith(('/status', '/footprint')) else 'volatile'
        recording = open_recording(recorded['path'])
        assert recording.topics[channel.topic].qos[0]['durability'] == durability
    assert topics == TYPES
    assert open_recording(recorded['path']).metadata['fastep']['radius/r2'] == '0.6'


def test_every_message_decodes_alike_with_rosbags_and_rclpy(recorded: dict[str, Any]) -> None:
    ours = list(open_recording(recorded['path']).messages())
    with AnyReader([recorded['path']]) as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == TYPES
        theirs = [(c.topic, c.msgtype, t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages()]
    assert len(ours) == len(theirs) == open_recording(recorded['path']).message_count
    assert Counter(m.topic for m in ours) == Counter(t[0] for t in theirs)
    # Same order within each topic (log-time order across topics may break ties differently).
    by_topic: dict[str, list[Any]] = {}
    for topic, msgtype, log_time, msg in theirs:
        by_topic.setdefault(topic, []).append((msgtype, log_time, msg))
    index = Counter()
    for m in ours:
        msgtype, log_time, msg = by_topic[m.topic][index[m.topic]]
        index[m.topic] += 1
        assert m.type == msgtype == TYPES[m.topic]
        assert m.log_time == log_time
        # rclpy's class; rosbags' for tf2_msgs, which has no rclpy class here
        assert type(m.message).__name__ in (msgtype.split('/')[-1], msgtype.replace('/', '__'))
        same(plain(m.message), plain(msg), m.topic)


def test_recording_matches_the_run(recorded: dict[str, Any]) -> None:
    import json
    run = json.loads(recorded['json'].read_text())['runs'][0]['robots']
    counts = open_recording(recorded['path']).counts()
    msgs = list(open_recording(recorded['path']).messages(['/r1/status', '/r2/status', '/r1/odom', '/r1/goal_pose']))
    for robot in run:
        statuses = [m for m in msgs if m.topic == f'/{robot["name"]}/status']
        assert statuses[-1].message.message == ('arrived' if robot['reached'] else 'failed')
        if robot['reached']:
            assert statuses[-1].log_time == pytest.approx(robot['sim_time'] * 1e9, abs=1e3)
        assert counts[f'/{robot["name"]}/goal_pose'] == 1
        assert counts[f'/{robot["name"]}/odom'] == counts[f'/{robot["name"]}/cmd_vel']
    odom = [m for m in msgs if m.topic == '/r1/odom']
    assert odom[0].log_time == 0 and (odom[0].message.pose.pose.position.x, odom[0].message.pose.pose.position.y) \
        == (2.0, 6.0)
    for m in odom:  # header.stamp is the log time
        assert m.message.header.stamp.sec * 10**9 + m.message.header.stamp.nanosec == m.log_time
    assert counts['/map'] == counts['/obstacles'] == 1
    assert counts['/r2/trailer_pose'] == counts['/r2/odom'] and '/r1/trailer_pose' not in counts


# ----------------------------------------------------------------------------------------------- truncation

@pytest.fixture(scope='module')
def small_chunks(recorded: dict[str, Any]) -> Path:
    """The recording re-chunked in 8 KiB chunks, so that cutting it leaves complete chunks."""
    out = recorded['folder'] / 'small_chunks.mcap'
    copy_recording(open_recording(recorded['path']), out, chunk_size=8192)
    return out


@pytest.mark.parametrize('keep', [0.3, 0.77])
def test_truncated_file_gives_its_complete_part(small_chunks: Path, tmp_path: Path, keep: float) -> None:
    data = small_chunks.read_bytes()
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(data[:int(len(data) * keep)])
    full = list(open_recording(small_chunks).raw_messages())
    recording = open_recording(cut)
    assert recording.truncated and recording.problem
    got = list(recording.messages())
    assert 0 < len(got) == recording.message_count < len(full)
    assert 'truncated' in recording.warning() and f'recovered {len(got)} messages' in recording.warning()
    assert '\n' not in recording.warning()
    # What is recovered is exactly the messages written before the cut (the file is in log-time order).
    assert [(m.topic, m.log_time) for m in got] == [(m.topic, m.log_time) for m in full[:len(got)]]
    assert isinstance(got[0].message, type(next(iter(open_recording(small_chunks).messages()))[3]))

    fixed = tmp_path / 'fixed.mcap'
    assert recover.main([str(cut), str(fixed)]) == 0
    again = open_recording(fixed)
    assert not again.truncated and again.message_count == len(got)
    with AnyReader([fixed]) as reader:
        assert reader.message_count == len(got)


def test_unreadable_files_give_one_line_errors(small_chunks: Path, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    data = small_chunks.read_bytes()
    cases = {'magic.mcap': (data[:5], TruncatedRecordingError), 'header.mcap': (data[:40], TruncatedRecordingError),
             'text.mcap': (b'not a recording\n', NotMcapError), 'empty.mcap': (b'', NotMcapError)}
    for name, (content, error) in cases.items():
        path = tmp_path / name
        path.write_bytes(content)
        with pytest.raises(error) as info:
            open_recording(path)
        assert '\n' not in str(info.value) and name in str(info.value)
        assert recover.main([str(path), str(tmp_path / 'out.mcap')]) == 2
        err = capsys.readouterr().err
        assert err.count('\n') == 1 and err.startswith('fastep-recover: error:')
    with pytest.raises(RecordingError, match='no such file'):
        open_recording(tmp_path / 'missing.mcap')


def test_fastep_sim_mcap_records_the_first_run_and_reports_bad_paths(
        recorded: dict[str, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'deep' / 'two.mcap'
    assert sim_cli.main(['table2_s1', '--seed', '4', '--runs', '2', '--mcap', str(out)]) == 0
    assert 'seed 4' in capsys.readouterr().out
    assert open_recording(out).metadata['fastep']['seed'] == '4'
    assert sim_cli.main(['table2_s1', '--mcap', str(tmp_path)]) == 2  # a folder
    err = capsys.readouterr().err
    assert err.startswith('fastep-sim: error:') and err.count('\n') == 1


def test_a_channels_qos_text_is_read_within_bounds() -> None:
    """offered_qos_profiles is YAML from whoever wrote the file: an alias bomb in it is no profile, not a hang."""
    from msg_tools.ros2_profile import parse_qos_yaml, qos_yaml
    profile = qos_dict()
    assert parse_qos_yaml(qos_yaml([profile])) == [profile]
    levels = 'abcdefghij'
    bomb = '- &a [x, x, x, x, x, x, x, x, x, x]\n' + ''.join(
        f'- &{name} [{", ".join([f"*{below}"] * 10)}]\n' for below, name in zip(levels, levels[1:]))
    bomb += '- {history: keep_last, depth: *j}\n'   # before: a "profile" of 10^10 items, hung whoever printed it
    assert parse_qos_yaml(bomb) == []
