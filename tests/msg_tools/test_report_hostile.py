"""fastep-report on hostile recordings (issue "Hardening", items 8 and 9): other message types on fastep topic
names, cut-off CDR in its fast decoding path, non-finite or huge odometry, a NaN radius or a bad workspace in
the metadata. Each gives a report (exit 0, strict JSON, a warning line saying what was left out) or one error
line (exit 2) - never a traceback, never NaN or Infinity in report.json.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message
from std_msgs.msg import Float64, String

from fastep_core.geometry import Circle
from fastep_core.world import World
from msg_tools import convert, report
from msg_tools.mcap_io import McapWriter

GOOD_ODOM = serialize_message(convert.state_to_odometry(np.array([1.0, 2.0])))


def odometry(x: float, y: float, vx: float = 0.0) -> Odometry:
    msg = Odometry()   # built by hand: convert.state_to_odometry refuses what these tests need
    msg.pose.pose.position.x, msg.pose.pose.position.y = float(x), float(y)
    msg.pose.pose.orientation.w = 1.0
    msg.twist.twist.linear.x = float(vx)
    return msg


def run_file(path: Path, *, odom: list[tuple[float, float]] | None = None, meta: dict[str, str] | None = None,
             with_map: bool = True, extra: Callable[[McapWriter], None] | None = None) -> Path:
    """A small run of robot r1 (50 odometry samples, commands, costs, a goal, an arrival) among one circle."""
    with McapWriter(path) as w:
        w.add_metadata('fastep', meta if meta is not None else {'robots': 'r1', 'radius/r1': '0.5'})
        world = World.from_obstacles([0, 0, 10, 10], [Circle((5.0, 5.0), 1.0)])
        w.write('/obstacles', convert.obstacles_to_marker_array(world.obstacle_list), 0)
        if with_map:
            w.write('/map', convert.world_to_occupancy_grid(world, 0.5), 0)
        w.write('/r1/goal_pose', convert.point_to_pose_stamped((9.0, 9.0)), 0)
        points = odom if odom is not None else [(1.0 + 0.1 * i, 1.0 + 0.1 * i) for i in range(50)]
        for i, (x, y) in enumerate(points):
            t = (i + 1) * 100_000_000
            w.write('/r1/odom', odometry(x, y), t)
            w.write('/r1/cmd_vel', Twist(), t)
            w.write('/r1/cost', Float64(data=1.0), t)
        w.write('/r1/status', convert.make_status('/r1', 'arrived', 'ok', {'reason': 'goal reached'}), 6_000_000_000)
        if extra is not None:
            extra(w)
    return path


def on(topic: str, type_name: str, data: bytes) -> Callable[[McapWriter], None]:
    """Writes `data` as one message of type_name on topic (a channel of that type)."""
    def write(w: McapWriter) -> None:
        w.write(topic, data, 7_000_000_000, type_name=type_name)
    return write


def strict_json(path: Path) -> Any:
    def refuse(constant: str) -> None:
        raise AssertionError(f'{path} holds {constant}: not JSON')
    return json.loads(path.read_text(), parse_constant=refuse)


def run_report(path: Path, capsys: pytest.CaptureFixture[str], figures: bool = True) -> tuple[int, str, Any]:
    out = path.with_suffix('')
    code = report.main([str(path), '--out', str(out), *([] if figures else ['--no-figures'])])
    err = capsys.readouterr().err
    assert 'Traceback' not in err and err.count('\n') <= 1, err
    doc = strict_json(out / 'report.json') if code == 0 else None
    return code, err, doc


@pytest.mark.parametrize('since, expected', [('5.0', 5.0), (None, 6.0), ('x', 6.0), ('nan', 6.0), ('7.0', 6.0),
                                             ('-1.0', 6.0)])
def test_an_arrival_counts_from_when_it_began(tmp_path: Path, since: str | None, expected: float,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """An arrived status logged at 6 s by a recorder some ticks behind, saying it began (`since`) at 5 s: the run
    took 5 s. Without `since`, or with one that cannot be (not a number, after the log time, before the goal):
    the log time."""
    values = {'reason': 'goal reached'} if since is None else {'reason': 'goal reached', 'since': since}
    path = tmp_path / 'late.mcap'
    with McapWriter(path) as w:
        w.add_metadata('fastep', {'robots': 'r1', 'radius/r1': '0.5'})
        w.write('/r1/goal_pose', convert.point_to_pose_stamped((9.0, 9.0)), 0)
        for i in range(10):
            w.write('/r1/odom', odometry(1.0 + 0.5 * i, 1.0), (i + 1) * 500_000_000)
        w.write('/r1/status', convert.make_status('/r1', 'arrived', 'ok', values), 6_000_000_000)
    code, _, doc = run_report(path, capsys, figures=False)
    assert code == 0 and doc['robots'][0]['reached']
    assert doc['robots'][0]['time_to_goal'] == pytest.approx(expected)


WRONG_TYPES = ['/r1/odom', '/r1/cmd_vel', '/r1/cost', '/r1/status', '/r1/waypoint', '/r1/plan', '/r1/goal_pose',
               '/obstacles', '/map']


@pytest.mark.parametrize('topic', WRONG_TYPES)
def test_another_type_on_a_fastep_topic_is_left_out(tmp_path: Path, topic: str,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """A std_msgs/String on a fastep topic name (in a file where the real one is missing)."""
    path = tmp_path / 'wrong.mcap'
    with McapWriter(path) as w:
        w.add_metadata('fastep', {'robots': 'r1'})
        w.write(topic, String(data='hello'), 1)
        if topic != '/r1/odom':
            w.write('/r1/odom', odometry(1.0, 2.0), 2)
    code, err, doc = run_report(path, capsys)
    if topic == '/r1/odom':    # the robot still has its name, but nothing of it is readable
        assert code == 0 and doc['robots'][0]['odom_messages'] == 0
    else:
        assert code == 0 and doc['robots'][0]['odom_messages'] == 1
    assert f'{topic} left out: it holds std_msgs/msg/String' in doc['warning'] and 'warning' in err


CUT_ODOM = {'header': GOOD_ODOM[:30], 'covariance': GOOD_ODOM[:500], 'last byte': GOOD_ODOM[:-1],
            'a huge frame name': GOOD_ODOM[:12] + b'\xff\xff\xff\x7f' + GOOD_ODOM[16:]}


@pytest.mark.parametrize('cut', list(CUT_ODOM))
def test_cut_off_odometry_is_skipped_like_rclpy_refuses_it(tmp_path: Path, cut: str,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    data = CUT_ODOM[cut]
    with pytest.raises(ValueError):
        report.odometry_fields(data)
    path = run_file(tmp_path / 'cut.mcap', extra=on('/r1/odom', 'nav_msgs/msg/Odometry', data))
    code, err, doc = run_report(path, capsys, figures=False)
    assert code == 0 and doc['robots'][0]['odom_messages'] == 50
    assert '1 message(s) on /r1/odom left out (CdrError: cut off' in doc['warning']


@pytest.mark.parametrize('topic,type_name,data', [
    ('/r1/cmd_vel', 'geometry_msgs/msg/Twist', b'\x00\x01\x00\x00' + bytes(10)),
    ('/r1/cost', 'std_msgs/msg/Float64', b'\x00\x01\x00\x00\x00'),
    ('/r1/status', 'diagnostic_msgs/msg/DiagnosticStatus', b'\x00\x01\x00\x00\x00'),
    ('/r1/plan', 'nav_msgs/msg/Path', b'\x00\x01\x00\x00' + bytes(3)),
    ('/r1/odom', 'nav_msgs/msg/Odometry', b'\x00\x00\x00\x00' + bytes(20)),   # big-endian CDR: rclpy's path
    ('/obstacles', 'visualization_msgs/msg/MarkerArray', b'\x00\x01\x00\x00\xff\xff\xff\xff'),
])
def test_undecodable_messages_are_counted_not_fatal(tmp_path: Path, topic: str, type_name: str, data: bytes,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    path = run_file(tmp_path / 'bad.mcap', extra=on(topic, type_name, data))
    code, err, doc = run_report(path, capsys, figures=False)
    assert code == 0 and doc['robots'][0]['odom_messages'] == 50 and doc['obstacles'] == 1
    assert f'1 message(s) on {topic} left out' in doc['warning']


def test_json_encoded_fastep_topics_are_left_out(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / 'json.mcap'
    with McapWriter(path) as w:
        schema = w.add_schema('nav_msgs/msg/Odometry', 'jsonschema', b'{}')
        channel = w.add_raw_channel('/r1/odom', 'json', schema)
        w.write_raw(channel, b'{"pose": 1}', 1)
        w.write('/r1/cost', Float64(data=2.0), 2)
    code, err, doc = run_report(path, capsys, figures=False)
    assert code == 0 and '/r1/odom left out: it holds nav_msgs/msg/Odometry (json)' in doc['warning']


@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf, 1e308, -1e308, 2e9])
def test_odometry_that_is_not_finite_or_huge_is_left_out(tmp_path: Path, bad: float,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    points = [(1.0 + 0.1 * i, 1.0) for i in range(20)]
    points[5] = (bad, 1.0)
    points[6] = (1.0, -bad)
    path = run_file(tmp_path / 'odom.mcap', odom=points)
    code, err, doc = run_report(path, capsys)
    row = doc['robots'][0]
    assert code == 0 and row['odom_messages'] == 18
    assert row['path_length'] == pytest.approx(1.9, abs=1e-9)   # 1.0 to 2.9 along x
    assert '2 message(s) on /r1/odom left out (not finite or beyond 1e+09)' in doc['warning']


@pytest.mark.parametrize('radius', ['nan', 'inf', '-1', 'abc', '1e308'])
def test_a_bad_radius_in_the_metadata_falls_back_with_a_warning(tmp_path: Path, radius: str,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    path = run_file(tmp_path / 'radius.mcap', meta={'robots': 'r1', 'radius/r1': radius})
    code, err, doc = run_report(path, capsys, figures=False)
    row = doc['robots'][0]
    assert code == 0 and row['radius'] == 0.5 and row['radius_source'] == 'default'
    assert row['min_clearance'] is not None and math.isfinite(row['min_clearance'])
    assert "radius/r1 = " in doc['warning'] and 'is not a radius' in doc['warning']


@pytest.mark.parametrize('workspace', ['0,0,nan,10', '10,10,0,0', '0,0,1e308,10', '0,0,10', 'a,b,c,d', '0,0,inf,1'])
def test_a_bad_workspace_in_the_metadata_is_left_out(tmp_path: Path, workspace: str,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    path = run_file(tmp_path / 'ws.mcap', meta={'robots': 'r1', 'workspace': workspace}, with_map=False)
    code, err, doc = run_report(path, capsys)
    assert code == 0 and doc['workspace'] is None
    assert "the metadata's workspace" in doc['warning']


def test_non_finite_values_never_reach_report_json(tmp_path: Path) -> None:
    """Whatever slips through, report.json is strict JSON: the writer turns NaN and Infinity into null."""
    assert report._json_ready({'a': [math.nan, 1.0, {'b': math.inf}], 'c': 'x'}) == {'a': [None, 1.0, {'b': None}],
                                                                                     'c': 'x'}
