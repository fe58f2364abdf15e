"""fastep-record against a live publisher: nothing lost, a complete file after SIGINT or SIGTERM, a
recoverable one after SIGKILL.

One isolated graph: the map node (latched /map and /obstacles, published before any recorder exists), three
recorders, and fastep_testing.fake_robots publishing odom and cost of two robots at 50 Hz once all recorders are
subscribed. Then the recorders get SIGINT, SIGTERM and SIGKILL.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Iterator

import pytest
from mcap.reader import SeekingReader
from rosbags.highlevel import AnyReader

from fastep_testing.graph import ROOT, Graph
from msg_tools import recover
from msg_tools.mcap_io import open_recording

COUNT = 100  # messages per topic, 2 s at 50 Hz
# Robot names of this test run only: a concurrent run on the same domain cannot add messages to them.
PREFIX = f'rec{os.getpid()}_'
TOPICS = [f'/{PREFIX}{k}/{what}' for k in (1, 2) for what in ('odom', 'cost')]


@pytest.fixture(scope='module')
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    g = Graph(tmp_path_factory.mktemp('recorder'))
    try:
        g.start('map', 'map_server', scenario='table2_s1')
        files = {'int': g.tmp / 'int.mcap', 'term': g.tmp / 'term.mcap', 'kill': g.tmp / 'kill.mcap'}
        g.start('rec_int', 'recorder', output=str(files['int']))
        g.start('rec_term', 'recorder', output=str(files['term']))
        g.start('rec_kill', 'recorder', output=str(files['kill']), chunk_size=4096, flush_period=0.2)
        fake = subprocess.run(
            [sys.executable, '-m', 'fastep_testing.fake_robots', '--robots', '2', '--rate', '50', '--count', str(COUNT),
             '--wait-subscribers', '3', '--wait-timeout', '90', '--prefix', PREFIX],
            env=g.env, cwd=ROOT, capture_output=True, text=True, timeout=180)
        assert fake.returncode == 0, fake.stderr
        published = json.loads(fake.stdout.strip().splitlines()[-1])['published']
        time.sleep(1.0)  # several flush periods of the SIGKILL recorder
        codes = {'kill': g.stop('rec_kill', signal.SIGKILL), 'int': g.stop('rec_int', signal.SIGINT),
                 'term': g.stop('rec_term', signal.SIGTERM)}
        yield {'files': files, 'published': published, 'codes': codes, 'graph': g}
    finally:
        g.close()


@pytest.mark.parametrize('how', ['int', 'term'])
def test_sigint_or_sigterm_leave_a_complete_file_with_everything(recorded: dict[str, Any], how: str) -> None:
    path = recorded['files'][how]
    assert recorded['codes'][how] == 0, recorded['graph'].log(f'rec_{how}')
    with open(path, 'rb') as f:
        reader = SeekingReader(f)
        assert reader.get_header().profile == 'ros2'
        summary = reader.get_summary()
    assert summary is not None and summary.statistics is not None
    recording = open_recording(path)
    assert not recording.truncated
    counts = recording.counts()
    assert recorded['published'] == {t: COUNT for t in TOPICS}
    for topic, sent in recorded['published'].items():
        assert counts[topic] == sent, f'{topic}: {counts[topic]} of {sent} recorded'
    # Latched topics published before the recorder started are there, and keep their QoS.
    assert counts['/map'] == counts['/obstacles'] == 1
    assert recording.topics['/map'].qos[0]['durability'] == 'transient_local'
    assert recording.topics[TOPICS[0]].qos[0]['durability'] == 'volatile'
    values = [m.message.pose.pose.position.x for m in recording.messages([TOPICS[0]])]
    assert values == [float(i) for i in range(COUNT)]
    with AnyReader([path]) as reader:
        assert reader.message_count == recording.message_count
        assert sum(1 for c, _, _ in reader.messages() if c.topic in TOPICS) == len(TOPICS) * COUNT


def test_sigkill_leaves_a_recoverable_file(recorded: dict[str, Any], tmp_path: Path) -> None:
    path = recorded['files']['kill']
    assert recorded['codes']['kill'] == -signal.SIGKILL
    recording = open_recording(path)
    assert recording.truncated
    assert 0 < recording.message_count
    messages = list(recording.messages())  # every recovered message decodes
    assert len(messages) == recording.message_count
    # Flushed every 0.2 s and killed 1 s after the last message: nothing of the publisher's was lost.
    counts = recording.counts()
    assert all(counts.get(topic, 0) == COUNT for topic in recorded['published'])

    fixed = tmp_path / 'fixed.mcap'
    assert recover.main([str(path), str(fixed)]) == 0
    again = open_recording(fixed)
    assert not again.truncated and again.counts() == counts
    with AnyReader([fixed]) as reader:
        assert reader.message_count == recording.message_count


def test_live_run_recording_reports_like_an_offline_one(tmp_path: Path) -> None:
    """map, plant, planner and clock on simulated time, recorded with use_sim_time: fastep-report reads the
    live file as it reads a fastep-sim one (same topics), and replays are driven by the same QoS metadata."""
    from diagnostic_msgs.msg import DiagnosticStatus
    from geometry_msgs.msg import PoseStamped

    from fastep_testing.graph import FAST, ONE_CIRCLE, Helper, write
    from msg_tools import convert, report
    from msg_tools.interface import RELIABLE, STATUS_QOS

    g = Graph(tmp_path)
    try:
        scenario = write(g.tmp / 'one.yaml', ONE_CIRCLE)
        out = g.tmp / 'live.mcap'
        g.start('map', 'map_server', scenario=str(scenario))
        g.start('rec', 'recorder', output=str(out), scenario=str(scenario), use_sim_time=True, clock_ack=True)
        g.start('plant', 'plant', '/r1', model='point_mass', start=[2.0, 10.0], use_sim_time=True)
        g.start('planner', 'planner', '/r1', model='point_mass', robot_radius=0.5, use_sim_time=True, **FAST)
        # Time holds at 0 until the plant, the planner, the recorder (twice: its time source, and to record it)
        # and, last, the helper follow /clock. Then in lock step, as fastep-launch runs a recorded graph: a free
        # clock at rtf 10 let a planner starved at load 9-15 drive 27 m of a 16 m route (compute time is time), so
        # no bound on the path could hold at any load; in lock step the run is the one a quiet machine makes.
        g.start('clock', 'clock', rtf=10.0, step=0.05, wait_for_subscribers=5,
                sync_topics=['/r1/cmd_vel', '/r1/odom'], observer_topics=['/recorder/clock_ack'], observer_lag=20)
        h = g.helper = Helper(g.domain)
        h.record_status('/r1')
        h.wait_status('/r1', lambda s: s['message'] == 'idle', 90.0, 'the planner to know the world')
        # The recorder says what it has received: its status counts the plant's start state before time runs.
        said = h.record('/recorder/recording', DiagnosticStatus, STATUS_QOS)
        h.spin_until(lambda: any(v.key == '/r1/odom' for m in said for v in m.values), 60.0,
                     'the recorder to hear /r1/odom')
        h.follow_clock()
        goal = h.node.create_publisher(PoseStamped, '/r1/goal_pose', RELIABLE)
        # The planner and the recorder must both have matched the goal publisher before it sends.
        h.spin_until(lambda: goal.get_subscription_count() >= 2, 60.0, 'the planner and the recorder on goal_pose')
        goal.publish(convert.point_to_pose_stamped((18.0, 10.5)))
        h.wait_status('/r1', lambda s: s['message'] == 'arrived', 120.0, 'arrival')
        h.spin_for(1.0)
        assert g.stop('rec', signal.SIGINT) == 0, g.log('rec')
    finally:
        g.close()
    recording = open_recording(out)
    assert not recording.truncated
    counts = recording.counts()
    for topic in ('/map', '/obstacles', '/clock', '/r1/odom', '/r1/cmd_vel', '/r1/cost', '/r1/status',
                  '/r1/plan', '/r1/goal_pose', '/r1/waypoint'):
        assert counts.get(topic, 0) > 0, f'nothing recorded on {topic}: {counts}'
    doc, _ = report.write_report(out, tmp_path / 'report', figures=False)
    row = doc['robots'][0]
    assert doc['scenario'] == 'one_circle' and doc['algorithm'] == 'fastep' and doc['obstacles'] == 1
    assert row['name'] == 'r1' and row['reached'] and row['radius_source'] == 'metadata'
    assert 16.0 < row["path_length"] < 16.0 * 1.5
    assert 0.0 < row['time_to_goal'] < 60.0 and row['min_clearance'] > 0.0 and row['activations'] >= 1
    # Log times are simulated time (the goal was sent at about 0 s of it).
    assert recording.end_time * 1e-9 < 100.0
    # The run is there from its start: the start state, stamped 0, before the first step.
    first = next(recording.messages(['/r1/odom'])).message
    assert convert.stamp_to_seconds(first.header.stamp) == 0.0 and convert.odometry_position(first) == (2.0, 10.0)


def test_bad_parameters_are_one_line_and_exit_2(tmp_path: Path) -> None:
    from fastep_testing.graph import free_domain, isolated_env
    env = isolated_env(free_domain(), tmp_path / 'log')
    for params in (['-p', f'output:={tmp_path}'], ['-p', f'output:={tmp_path / "x.mcap"}', '-p', 'compression:=rar']):
        proc = subprocess.run([sys.executable, '-m', 'fastep_ros.recorder', '--ros-args', *params], env=env,
                              cwd=ROOT, capture_output=True, text=True, timeout=60)
        assert proc.returncode == 2
        assert proc.stderr.startswith('fastep-record: error:') and proc.stderr.count('\n') == 1, proc.stderr


# Issue "Hardening", item 15: a full disk. Simulated without filling the real one: a file size limit
# (RLIMIT_FSIZE, set in the recorder's process only: writes past it fail with EFBIG) or /dev/full (ENOSPC).
FULL_LIMIT = 64 * 1024


def _limit_file_size() -> None:
    resource.setrlimit(resource.RLIMIT_FSIZE, (FULL_LIMIT, FULL_LIMIT))


@pytest.mark.parametrize('how', ['file_size_limit', 'dev_full'])
def test_a_full_disk_stops_the_recorder_with_one_line_and_keeps_what_was_written(tmp_path: Path, how: str) -> None:
    from fastep_testing.graph import free_domain, isolated_env
    env = isolated_env(free_domain(), tmp_path / 'log')
    prefix = f'full{os.getpid()}_'
    out = tmp_path / 'full.mcap' if how == 'file_size_limit' else Path('/dev/full')
    recorder = subprocess.Popen(
        [sys.executable, '-m', 'fastep_ros.recorder', '--ros-args', '--log-level', 'warn', '-p', f'output:={out}',
         '-p', 'chunk_size:=1024', '-p', 'flush_period:=0.1', '-p', 'compression:=none'],
        env=env, cwd=ROOT, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=_limit_file_size if how == 'file_size_limit' else None)
    try:
        if how == 'file_size_limit':   # /dev/full refuses the first flush (the header), before any message
            fake = subprocess.run(
                [sys.executable, '-m', 'fastep_testing.fake_robots', '--robots', '2', '--rate', '200', '--count',
                 '300', '--wait-subscribers', '1', '--wait-timeout', '90', '--prefix', prefix],
                env=env, cwd=ROOT, capture_output=True, text=True, timeout=180)
            assert fake.returncode == 0, fake.stderr
        _, err = recorder.communicate(timeout=60)   # it stops by itself
    finally:
        if recorder.poll() is None:
            recorder.kill()
            recorder.wait()
    errors = [line for line in err.splitlines() if 'error' in line.lower() or 'Traceback' in line]
    assert recorder.returncode == 1 and len(errors) == 1, err
    reason = 'File too large' if how == 'file_size_limit' else 'No space left on device'
    assert errors[0].startswith(f'fastep-record: error: cannot write {out}: {reason}; recording stopped after')
    if how == 'dev_full':
        return
    recording = open_recording(out)   # everything up to the last chunk that fitted
    assert recording.truncated and 0 < recording.message_count
    assert len(list(recording.messages())) == recording.message_count
    fixed = tmp_path / 'fixed.mcap'
    assert recover.main([str(out), str(fixed)]) == 0
    with AnyReader([fixed]) as reader:
        assert reader.message_count == recording.message_count
