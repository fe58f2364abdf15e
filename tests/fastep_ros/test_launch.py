"""fastep-launch end to end, and the one-line exit-2 errors of the launcher and the nodes."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from rosbags.highlevel import AnyReader

from fastep_core.planning.algorithms import DEFAULT_ALGORITHM
from fastep_core.scenario import load_scenario
from fastep_core.simulator import simulate
from fastep_testing.graph import ONE_CIRCLE, free_domain, isolated_env, stop_process, without_dds_noise, write


def run(cmd: list[str], env: dict[str, str], timeout: float) -> subprocess.CompletedProcess[str]:
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL)
    try:
        out, err = proc.communicate(timeout=timeout)
    finally:
        stop_process(proc)
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


def children(pid: int) -> list[int]:
    out = subprocess.run(['ps', '-o', 'pid=', '--ppid', str(pid)], capture_output=True, text=True).stdout
    return [int(p) for p in out.split()]


def alive(pid: int) -> bool:
    try:
        state = Path(f'/proc/{pid}/stat').read_text().split(')')[-1].split()[0]
    except OSError:
        return False
    return state != 'Z'


def test_launch_runs_a_scenario_like_fastep_sim(tmp_path: Path) -> None:
    scenario = write(tmp_path / 'one.yaml', ONE_CIRCLE)
    out, plot, recorded = tmp_path / 'live.json', tmp_path / 'live.png', tmp_path / 'live.mcap'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    result = run([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--rtf', '10', '--seed', '0',
                  '--json', str(out), '--plot', str(plot), '--record', str(recorded)], env, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    assert 'Traceback' not in result.stderr
    assert 'one_circle: 1 robot(s) on their way' in result.stdout
    lines = [line for line in result.stdout.splitlines() if line.startswith('r1:')]
    assert len(lines) == 1 and 'arrived' in lines[0], result.stdout
    assert plot.stat().st_size > 0

    live = json.loads(out.read_text())
    reference = simulate(load_scenario(str(scenario)), DEFAULT_ALGORITHM, 0)   # the launcher's default
    assert live['scenario'] == 'one_circle' and live['algorithm'] == DEFAULT_ALGORITHM
    for robot, sim in zip(live['runs'][0]['robots'], reference.robots):
        assert robot['name'] == sim.name
        assert robot['reached'] and sim.reached
        assert not robot['collided']
        # The swarm draws the same random streams, but the live loop sees odometry a little later than the
        # in-process one, so its steps differ slightly: compare with a tolerance.
        assert robot['path_length'] == pytest.approx(sim.path_length, rel=0.05)
        assert robot['sim_time'] == pytest.approx(sim.sim_time, rel=0.15)
        rows = robot['trajectory']
        assert rows[0][1:3] == pytest.approx([2.0, 10.0], abs=1e-6)
        # one odometry message per control tick (lock step): at 2 m/s rows are at most ~0.12 m apart
        assert max(((b[1] - a[1]) ** 2 + (b[2] - a[2]) ** 2) ** 0.5 for a, b in zip(rows, rows[1:])) <= 0.15
    # The recording holds the whole run, from the start state (stamped 0, before the clock started) on.
    with AnyReader([recorded]) as reader:   # rosbags: a reader independent of ours
        connections = [c for c in reader.connections if c.topic == '/r1/odom']
        odometry = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=connections)]
        # REP-105 TF, derived by the recorder from the odometry it records (Foxglove draws the robot with it).
        tf = {c.topic: [reader.deserialize(raw, c.msgtype) for _, _, raw in reader.messages(connections=[c])]
              for c in reader.connections if c.topic in ('/tf', '/tf_static')}
        # The goal, recorded before the clock started (fastep-report times the run from it).
        goals = [t for _, t, _ in reader.messages(connections=[c for c in reader.connections
                                                                if c.topic == '/r1/goal_pose'])]
    assert goals and goals[0] == 0, goals
    stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in odometry]
    assert stamps[0] == 0.0 and (odometry[0].pose.pose.position.x, odometry[0].pose.pose.position.y) == (2.0, 10.0)
    assert stamps[-1] >= rows[-1][0] - 1e-9
    assert_every_tick(stamps)
    assert {(m.header.frame_id, m.child_frame_id) for m in odometry} == {('r1/odom', 'r1/base_link')}
    assert [(t.header.frame_id, t.child_frame_id) for m in tf['/tf_static'] for t in m.transforms] == \
        [('map', 'r1/odom')]
    assert len(tf['/tf']) == len(odometry)
    last = tf['/tf'][-1].transforms[0]
    assert (last.header.frame_id, last.child_frame_id) == ('r1/odom', 'r1/base_link')
    assert (last.transform.translation.x, last.transform.translation.y) == \
        (odometry[-1].pose.pose.position.x, odometry[-1].pose.pose.position.y)


def test_launch_realtime_counts_planning_latency_in_lock_step_and_arrives(tmp_path: Path) -> None:
    """--realtime: the planners drive on their planning thread's newest plan while the simulated clock goes on
    (their status carries planning_ms, which only the thread measures); the robot arrives without touching."""
    scenario = write(tmp_path / 'one.yaml', ONE_CIRCLE)
    recorded = tmp_path / 'live.mcap'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    result = run([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--realtime', '--rtf', '4',
                  '--record', str(recorded), '--no-progress'], env, timeout=150)
    assert result.returncode == 0, result.stdout + result.stderr
    lines = [line for line in result.stdout.splitlines() if line.startswith('r1:')]
    assert len(lines) == 1 and 'arrived' in lines[0], result.stdout
    with AnyReader([recorded]) as reader:
        connections = [c for c in reader.connections if c.topic == '/r1/status']
        statuses = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=connections)]
    planning = [kv.value for m in statuses for kv in m.values if kv.key == 'planning_ms']
    assert any(planning), 'no planning pass was timed: the planner did not plan on its thread'
    bad = run([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--realtime', '--no-clock'], env, 30)
    assert bad.returncode == 2 and '--realtime is for lock step' in bad.stderr


def assert_every_tick(stamps: list[float], dt: float = 0.05) -> None:
    """Odometry of a lock-step run as recorded: the start state (stamped 0, repeated until the clock starts), then
    one message a tick, none missing: the recorder, which may lag the clock a few ticks, lost nothing."""
    assert stamps == sorted(stamps)
    ticks = [round(t / dt) for t in stamps if t > 0.0]
    assert ticks == list(range(1, len(ticks) + 1)), 'a tick is missing from the recording'
    assert max(abs(t - k * dt) for t, k in zip([t for t in stamps if t > 0.0], ticks)) < 1e-6


def test_a_recorded_run_interrupted_keeps_every_tick_up_to_where_it_stopped(tmp_path: Path) -> None:
    """Ctrl-C in a recorded lock-step run at a high rtf: the file is finished, and it holds every tick from the
    start to where the run stopped (the recorder lags the clock by a few ticks at most, and the launcher lets it
    reach the time it stopped at before it stops the nodes)."""
    recorded = tmp_path / 'cut.mcap'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    # make demo's run: 61.5 s of simulated time, at rtf 10 at least 6 s of wall time (at rtf 50 it ended before the
    # Ctrl-C, 1.2 s after it began)
    proc = subprocess.Popen([sys.executable, '-m', 'fastep_ros.launch', 'case_study_1', '--rtf', '10', '--record',
                             str(recorded), '--no-progress'], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    try:
        assert proc.stdout is not None
        line = first_line(proc)
        assert 'on their way' in line, line
        time.sleep(1.5)   # (the clock runs at 10x real time at most: 15 s of the 61.5)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        stop_process(proc)
    assert proc.returncode == 1 and 'interrupted' in err and 'Traceback' not in err, err
    assert f'wrote {recorded}' in out
    with AnyReader([recorded]) as reader:
        connections = [c for c in reader.connections if c.topic == '/r1/odom']
        stamps = [(m.header.stamp.sec + m.header.stamp.nanosec * 1e-9) for m in
                  (reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=connections))]
    assert 2.0 < stamps[-1] < 55.0, 'Ctrl-C came in the middle of the run'
    assert_every_tick(stamps)


def test_a_v2_world_runs_live_with_the_outcome_of_fastep_sim_judged_against_the_truth(tmp_path: Path) -> None:
    """crossing_movers (a known mover across the run, an obstacle missing from the map, one misplaced on it; the
    robot has a laser): fastep-map gives what the map knows and the mover on /movers, the plant scans the truth,
    the planner perceives and yields; the recording carries the scenario, and fastep-report judges the run
    against the truth (the mover where it was at each time): the same outcome as fastep-sim's."""
    from msg_tools.interface import SCENARIO_DATA
    from msg_tools.mcap_io import open_recording
    from msg_tools.report import load_run, metrics
    recorded, out = tmp_path / 'v2.mcap', tmp_path / 'v2.json'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    result = run([sys.executable, '-m', 'fastep_ros.launch', 'crossing_movers', '--rtf', '20', '--seed', '0',
                  '--json', str(out), '--record', str(recorded)], env, timeout=240)
    assert result.returncode == 0, result.stdout + result.stderr
    reference = simulate(load_scenario('crossing_movers'), DEFAULT_ALGORITHM, 0).robots[0]
    assert reference.reached and not reference.collided
    live = json.loads(out.read_text())['runs'][0]['robots'][0]
    assert live['reached'] and not live['collided'] and live['min_clearance'] > 0.0
    assert live['path_length'] == pytest.approx(reference.path_length, rel=0.05)
    run_ = load_run(open_recording(recorded))
    assert SCENARIO_DATA in run_.metadata and run_.truth() is not None
    row = metrics(run_)['robots'][0]
    assert row['reached'] and not row['collided']
    assert row['min_clearance'] == pytest.approx(live['min_clearance'], abs=0.05)
    with AnyReader([recorded]) as reader:
        statuses = [c for c in reader.connections if c.topic == '/r1/status']
        values = [{kv.key: kv.value for kv in reader.deserialize(raw, c.msgtype).values}
                  for c, _, raw in reader.messages(connections=statuses)]
    assert int(values[-1]['scans']) > 100                   # it perceived with the plant's scans ...
    assert any('mover 1' in v['reason'] or 'mover 0' in v['reason'] for v in values)   # ... and met the mover


def first_line(proc: subprocess.Popen[str]) -> str:
    """The first line of the launcher's stdout that is its own (Fast DDS writes its shared-memory errors there)."""
    assert proc.stdout is not None
    line = proc.stdout.readline()
    while line and not without_dds_noise(line).strip():
        line = proc.stdout.readline()
    return line


def launch_under_way(tmp_path: Path, domain: int | None = None,
                     layout: str = 'node') -> tuple[subprocess.Popen[str], list[int]]:
    """fastep-launch of one robot, once the goals are in and the clock runs, and its node processes."""
    scenario = write(tmp_path / 'one.yaml', ONE_CIRCLE)
    env = isolated_env(free_domain() if domain is None else domain, tmp_path / 'roslog')
    proc = subprocess.Popen([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--rtf', '0.5',
                             '--layout', layout], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
    assert proc.stdout is not None
    line = first_line(proc)  # printed once the goals are in and the clock runs
    if 'on their way' not in line:
        stop_process(proc)
        pytest.fail(f'fastep-launch did not start: {line!r}')
    return proc, children(proc.pid)


@pytest.mark.parametrize('layout,processes', [('node', 4), ('robot', 3), ('graph', 1)])
def test_launch_stops_every_node_on_ctrl_c(tmp_path: Path, layout: str, processes: int) -> None:
    proc, kids = launch_under_way(tmp_path, layout=layout)
    try:
        # map, plant, planner, clock: each in its own process; map, robot (plant + planner), clock; all in one
        assert len(kids) == processes, f'expected {processes} node processes with --layout {layout}, found {kids}'
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=20)
    finally:
        stop_process(proc)
    assert proc.returncode == 1
    assert 'interrupted' in err and 'Traceback' not in err
    assert not [pid for pid in kids if alive(pid)], 'a node outlived the launcher'


def test_launch_survives_a_second_ctrl_c_and_a_sigterm_while_it_stops_the_nodes(tmp_path: Path) -> None:
    """Signals only ask the launcher to stop: a second one while it stops the nodes is no traceback."""
    proc, kids = launch_under_way(tmp_path)
    try:
        for sig in (signal.SIGINT, signal.SIGINT, signal.SIGTERM):
            proc.send_signal(sig)
            time.sleep(0.1)
        _, err = proc.communicate(timeout=20)
    finally:
        stop_process(proc)
    assert proc.returncode == 1
    assert 'interrupted' in err and 'Traceback' not in err, err
    assert not [pid for pid in kids if alive(pid)], 'a node outlived the launcher'


@pytest.mark.parametrize('argv,words', [
    (['no_such_scenario_here'], 'no built-in scenario'),
    (['missing/file.yaml'], 'file not found'),
    (['open_field', '--rtf', '-1'], '--rtf must be in [0.001, 10000], got -1'),
    (['open_field', '--rtf', '1e-300'], '--rtf must be in [0.001, 10000], got 1e-300'),   # create_timer traceback
    (['open_field', '--seed', '-1'], 'a seed must be >= 0'),
    (['application', '--algorithm', 'dwa'],
     'dwa drives point_mass and diff_drive robots only; robot r1 is a tractor_trailer'),
    # Checked before the run (they were after it: --record DIR aborted with exit 1 once the nodes were up).
    (['open_field', '--record', '{tmp}'], '--record {tmp}: is a directory'),
    (['open_field', '--json', '{tmp}'], '--json {tmp}: is a directory'),
    (['open_field', '--plot', '{tmp}/p.xyz'], 'cannot draw a .xyz file'),
    (['open_field', '--json', '/dev/null/out.json'], 'cannot be written: File exists (/dev/null)'),
    # Names the scenario format allows but ROS does not: an rcl lexer error, an InvalidTopicNameException traceback.
    (['{tmp}/r__1.yaml'], "robots[0].name 'r__1' cannot name a robot on the ROS graph: ROS does not allow '__'"),
    (['{tmp}/long.yaml'], 'cannot name a robot on the ROS graph: 250 characters, more than the 200'),
])
def test_launch_bad_input_is_one_line_and_exit_2(tmp_path: Path, argv: list[str], words: str) -> None:
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    for name in ('r__1', 'a' * 250):
        robot = f'{{name: {name}, model: point_mass, start: [2, 2], goal: [18, 18], radius: 0.5}}'
        write(tmp_path / ('long.yaml' if len(name) > 4 else f'{name}.yaml'),
              f'workspace: [0, 0, 20, 20]\nrobots:\n  - {robot}\n')
    argv, words = [a.format(tmp=tmp_path) for a in argv], words.format(tmp=tmp_path)
    result = run([sys.executable, '-m', 'fastep_ros.launch', *argv], env, timeout=60)
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1 and words in result.stderr, result.stderr
    assert result.stdout == ''


@pytest.mark.parametrize('module,params,words', [
    ('map_server', ['scenario:=no_such_scenario_here'], 'no built-in scenario'),
    ('planner', ['algorithm:=dijkstra'], 'algorithm must be one of'),
    ('planner', ['algorithm:=dwa', 'model:=tractor_trailer'], 'dwa drives point_mass and diff_drive robots only'),
    ('planner', ['max_speed:=-1.0'], 'max_speed'),
    ('plant', ['model:=tractor_trailer', 'start:=[1.0, 2.0]'], 'start must have 4 values'),
    ('plant', ['start:=[.nan, 2.0]'], 'start must be finite'),
    ('planner', ['seed:=-4'], 'seed must be >= 0'),
    ('planner', ['a:=.inf'], 'must be finite'),
    ('planner', ['trap_timeout:=-1.0'], 'trap_timeout'),
    ('planner', ['n_fireflies:=many'], 'n_fireflies'),
    ('planner', ['workspace:=[0.0, 1.0]'], 'workspace must be'),
    ('planner', ['--garbage'], 'cannot start ROS'),
    # Rates and periods rclpy's create_timer overflowed on (a traceback), or that flooded the log.
    ('planner', ['control_rate_hz:=1e-12'], 'control_rate_hz must be in [0.1, 10000] Hz, got 1e-12'),
    ('plant', ['rate_hz:=1e-12'], 'rate_hz must be in [0.1, 10000] Hz'),
    ('plant', ['rate_hz:=1e12'], 'rate_hz must be in [0.1, 10000] Hz, got 1e+12'),
    ('recorder', ['flush_period:=1e300'], 'flush_period must be in [0.01, 3600] s'),
    ('recorder', ['discovery_period:=1e-12'], 'discovery_period must be in [0.01, 3600] s'),
    ('clock', ['rtf:=1e-300'], 'rtf must be in [0.001, 10000]'),
    ('clock', ['max_rate_hz:=1e-300'], 'max_rate_hz must be in [0.1, 10000] Hz'),
    ('clock', ['step:=1e300'], 'step must be in [0.0001, 10] s'),
    ('clock', ['start:=1e300'], 'start must be in [0, 1e+09] s'),
    ('clock', ['rtf:=1000.0', 'max_rate_hz:=0.1'], 'a tick of 10000 s'),
])
def test_nodes_refuse_bad_parameters_with_one_line(tmp_path: Path, module: str, params: list[str],
                                                   words: str) -> None:
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    cmd = [sys.executable, '-m', f'fastep_ros.{module}', '--ros-args']
    for p in params:
        cmd += [p] if p.startswith('--') else ['-p', p]
    result = run(cmd, env, timeout=60)
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1 and words in result.stderr, result.stderr
    assert 'Traceback' not in result.stderr


def test_a_trapped_tractor_trailer_manoeuvres_out_on_the_live_graph(tmp_path: Path) -> None:
    # The navigator's manoeuvre (planning/recovery/manoeuvre_search.py) replayed through the plant over DDS: commands a
    # tick late on a real graph must not throw it off its planned states for good.
    import yaml

    from fastep_core.experiments.random_worlds import u_trap
    robot = {'name': 'r1', 'model': 'tractor_trailer', 'start': [5, 15, 0.0, 0.0], 'goal': [35, 15], 'radius': 0.6,
             'length': 1.0, 'trailer_length': 1.0, 'width': 0.5}
    data = {'name': 'u_tractor', 'workspace': [0, 0, 40, 30],
            'obstacles': u_trap((20, 15), 3.5, 3.0, 3.141592653589793),
            'robots': [robot]}
    scenario = tmp_path / 'u.yaml'
    scenario.write_text(yaml.safe_dump(data))
    out = tmp_path / 'live.json'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    result = run([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--rtf', '20', '--seed', '0',
                  '--algorithm', 'fastep', '--json', str(out)], env, timeout=240)   # fastep_route goes round the trap
    assert result.returncode == 0, result.stdout + result.stderr
    live = json.loads(out.read_text())['runs'][0]['robots'][0]
    assert live['reached'] and not live['collided'] and live['escapes'] == 1 and live['manoeuvres'] >= 1, \
        (live, result.stdout)


def test_a_planner_on_a_far_seed_stream_starts_at_once_with_fastep_sims_stream(tmp_path: Path) -> None:
    """-p seed_stream:=2000000000 made the planner spawn two billion SeedSequences (~85 MB/s). Run under a 3 GB
    address-space limit, so the old code ends in MemoryError instead of taking the machine's memory."""
    import resource

    import numpy as np

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
    code = ('from rclpy.parameter import Parameter\n'
            'import rclpy\n'
            'rclpy.init()\n'
            'from fastep_ros.planner import PlannerNode\n'
            'node = PlannerNode(parameter_overrides=[Parameter("seed", value=7), '
            'Parameter("seed_stream", value=2_000_000_000)])\n'
            'print("rng", repr(node.rng.random()))\n'
            'node.destroy_node()\n'
            'rclpy.shutdown()\n')
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    env['MALLOC_ARENA_MAX'] = '2'   # address space reserved by glibc's per-thread arenas: not the thread count's
    proc = subprocess.Popen([sys.executable, '-c', code], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, stdin=subprocess.DEVNULL, preexec_fn=limit)
    try:
        out, err = proc.communicate(timeout=120)
    finally:
        stop_process(proc)
    assert proc.returncode == 0, err[-2000:]
    expected = np.random.default_rng(np.random.SeedSequence(7).spawn(3)[2]).random()
    from fastep_ros.planner import stream_rng
    assert stream_rng(7, 2).random() == expected, 'the k-th stream is the one fastep-sim gives its k-th robot'
    # Its line among whatever else the process prints (Fast DDS logs transport errors on stdout).
    drawn = [float(line.split()[1]) for line in out.splitlines() if line.startswith('rng ')]
    assert drawn == [np.random.default_rng(np.random.SeedSequence(7, spawn_key=(2_000_000_000,))).random()], out


def _foreign_publisher(context: Any, topic: str, msg_type: Any) -> Any:
    """A node of 'another graph' in this process, publishing on `topic` (discovery needs no spinning)."""
    import rclpy
    node = rclpy.create_node('someone_else', context=context)
    node.create_publisher(msg_type, topic, 10)
    return node


def test_launch_refuses_to_start_beside_another_graph(context: Any, tmp_path: Path) -> None:
    """Two launches on one domain drove each other's robots (one reported a 498 m path in a 50 m map): a launch
    that sees another graph's /clock (or its robots' topics) starts nothing and says so."""
    from rosgraph_msgs.msg import Clock
    other = _foreign_publisher(context, '/clock', Clock)
    try:
        scenario = write(tmp_path / 'one.yaml', ONE_CIRCLE)
        env = isolated_env(context.get_domain_id(), tmp_path / 'roslog')
        result = run([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--record', str(tmp_path / 'r.mcap')],
                     env, timeout=60)
    finally:
        other.destroy_node()
    assert result.returncode == 2, result.stdout + result.stderr
    err = without_dds_noise(result.stderr)
    assert len(err.strip().splitlines()) == 1 and 'Traceback' not in err, result.stderr
    # Seen before the nodes start ('/clock (1 publishers)'), or, when DDS is slow to show it (under load: seconds),
    # while they come up or once the run is under way: then it stops the run.
    assert f'another ROS graph shares ROS_DOMAIN_ID {context.get_domain_id()}: /clock (' in result.stderr


def test_launch_stops_when_another_graph_joins_its_robots_mid_run(context: Any, tmp_path: Path) -> None:
    from nav_msgs.msg import Odometry
    proc, kids = launch_under_way(tmp_path, context.get_domain_id())
    other = None
    try:
        other = _foreign_publisher(context, '/r1/odom', Odometry)
        _, err = proc.communicate(timeout=30)
    finally:
        stop_process(proc)
        if other is not None:
            other.destroy_node()
    assert proc.returncode == 2, err
    assert 'another ROS graph shares' in err and '/r1/odom (2 publishers, 1 of them this launch)' in err, err
    assert 'Traceback' not in err, err
    assert not [pid for pid in kids if alive(pid)], 'a node outlived the launcher'


@pytest.mark.parametrize('module', ['planner', 'recorder'])
def test_a_node_stops_cleanly_on_sigterm_and_a_second_signal(tmp_path: Path, module: str) -> None:
    """SIGTERM ended a node by its default action (rclpy's handler passes it on: exit -15, the recorder's file
    unfinished), and a second signal while the node stopped did the same."""
    from msg_tools.mcap_io import open_recording
    out = tmp_path / 'r.mcap'
    params = {'planner': ['workspace:=[0.0, 0.0, 10.0, 10.0]'], 'recorder': [f'output:={out}']}[module]
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    cmd = [sys.executable, '-m', f'fastep_ros.{module}', '--ros-args', *sum((['-p', p] for p in params), [])]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL)
    try:
        assert proc.stderr is not None
        first = proc.stderr.readline()   # its INFO line: the node is built and spins
        assert '[INFO]' in first, first
        for sig in (signal.SIGTERM, signal.SIGTERM, signal.SIGINT):
            proc.send_signal(sig)
            time.sleep(0.01)
        _, err = proc.communicate(timeout=30)
    finally:
        stop_process(proc)
    assert proc.returncode == 0 and 'Traceback' not in err, (proc.returncode, err)
    if module == 'recorder':
        open_recording(out)   # finished: summary and footer written


def test_a_node_interrupted_while_it_imports_ends_without_a_traceback(tmp_path: Path) -> None:
    """The moment is counted from the import of fastep_ros (its handler is then installed), not from the start: at
    load 15 a fixed 0.3 s from the start fell in the interpreter's own site module ("Fatal Python error:
    init_import_site", exit 1), which is Python's to handle, not the project's (as the test below says)."""
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    env['PYTHONPROFILEIMPORTTIME'] = '1'   # a line on stderr as each import ends: when fastep_ros is in
    proc = subprocess.Popen([sys.executable, '-m', 'fastep_ros.planner'], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        assert proc.stderr is not None
        head = []
        for line in proc.stderr:
            head.append(line)
            if line.rstrip().endswith('| fastep_ros'):
                break
        time.sleep(0.3)   # importing rclpy, numpy, scipy
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        stop_process(proc)
    err = ''.join(head) + err
    assert proc.returncode in (0, 130) and 'Traceback' not in err and 'Fatal' not in err, (proc.returncode, err)


def test_a_launched_node_stopped_at_any_moment_of_its_imports_exits_0_without_a_traceback(tmp_path: Path) -> None:
    """A launch that refuses to start (another graph on the domain) stops its nodes while they import: one stopped
    while rclpy's C extension initialised printed "ImportError: initialization failed" with two tracebacks (a red
    CI). The moments below are counted from the import of fastep_ros (its handler is then installed) and cover the
    imports after it (numpy, rclpy, the node's modules). A signal before that, while the interpreter itself starts
    (its site module), is Python's to handle: at 0.05 s from the start on a loaded machine that printed "Fatal
    Python error: init_import_site" (CI, issue Faults), not the project's to catch."""
    import os
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    env['FASTEP_PARENT_PID'] = str(os.getpid())   # started by "fastep-launch": this process
    env['PYTHONPROFILEIMPORTTIME'] = '1'          # a line on stderr as each import ends: when fastep_ros is in
    for delay in (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.5):
        proc = subprocess.Popen([sys.executable, '-m', 'fastep_ros.container', '--node', 'planner', '--node', 'plant'],
                                env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                stdin=subprocess.DEVNULL)
        try:
            assert proc.stderr is not None
            head = []
            for line in proc.stderr:
                head.append(line)
                if line.rstrip().endswith('| fastep_ros'):
                    break
            time.sleep(delay)
            proc.send_signal(signal.SIGINT)
            _, err = proc.communicate(timeout=30)
        finally:
            stop_process(proc)
        err = ''.join(head) + err
        assert proc.returncode == 0 and 'Traceback' not in err and 'Fatal' not in err, (delay, proc.returncode, err)


def test_a_stop_signal_before_rclpy_init_is_not_lost(tmp_path: Path) -> None:
    """The window between a node's own signal handlers and rclpy's (rclpy.init): a SIGINT there ended nothing, the
    node started and ran on. Now it is remembered and the node stops before it is built."""
    script = (
        'import os, signal\n'
        'from fastep_ros import common\n'
        'def build():\n'
        '    raise SystemExit("built after a stop signal")\n'
        'common._ignore_stop_signals()\n'
        'os.kill(os.getpid(), signal.SIGINT)   # lands in the window\n'
        'print("exit", common.node_main("test", build))\n')
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    done = subprocess.run([sys.executable, '-c', script], env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stdout.strip() == 'exit 0', (done.returncode, done.stdout, done.stderr)


def test_a_stop_signal_cleans_the_node_up_before_the_context_is_shut_down(tmp_path: Path) -> None:
    """SIGINT ends the spin loop; the executor and the node are torn down while the context is still up. rclpy's own
    handler shut the context down at any point of the spin, and rclpy 7.1.6's EventsExecutor, stopped so in the
    middle of taking a node's entities, aborted the process when destroyed (a red CI, 1 stop in about 80)."""
    script = (
        'import os, signal, threading, rclpy\n'
        'from rclpy.node import Node\n'
        'from fastep_ros import common\n'
        'class Probe(Node):\n'
        '    def __init__(self):\n'
        '        super().__init__("probe")\n'
        '        self.create_timer(0.01, lambda: None)\n'
        '        threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()\n'
        '    def destroy_node(self):\n'
        '        print("context up at clean-up:", self.context.ok(), flush=True)\n'
        '        super().destroy_node()\n'
        'print("exit", common.node_main("test", Probe, []))\n')
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    done = subprocess.run([sys.executable, '-c', script], env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and 'Traceback' not in done.stderr, (done.returncode, done.stderr)
    assert done.stdout.split('\n')[:2] == ['context up at clean-up: True', 'exit 0'], done.stdout


def test_a_full_disk_under_fastep_launch_is_not_reported_as_written(tmp_path: Path) -> None:
    """Issue "Hardening", item 15: the recorder's file hits a file size limit (RLIMIT_FSIZE of the launcher,
    inherited by every node; a full disk without filling one): the launcher must not print "wrote ..."."""
    import resource

    def limit_file_size() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (16 * 1024, 16 * 1024))

    scenario = write(tmp_path / 'one.yaml', ONE_CIRCLE)
    recorded = tmp_path / 'live.mcap'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    proc = subprocess.Popen([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--rtf', '10', '--seed', '0',
                             '--record', str(recorded)], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, stdin=subprocess.DEVNULL, preexec_fn=limit_file_size)
    try:
        out, err = proc.communicate(timeout=120)
    finally:
        stop_process(proc)
    assert proc.returncode == 1 and 'Traceback' not in err, out + err
    assert f'wrote {recorded}' not in out, out
    assert 'fastep-record: error: cannot write' in err and 'File too large' in err, err
    assert f'fastep-launch: error: the recorder failed (exit code 1): {recorded} is incomplete' in err, err


def test_the_plot_formats_known_without_matplotlib_are_matplotlibs() -> None:
    """--plot's usual suffixes are checked without importing matplotlib (before any node starts): each is one it
    draws."""
    from matplotlib.backend_bases import FigureCanvasBase

    from fastep_ros.launch import DRAWN_FORMATS
    assert DRAWN_FORMATS <= set(FigureCanvasBase.get_supported_filetypes())


def test_a_process_joins_dds_only_when_its_gate_opens(context: Any, tmp_path: Path) -> None:
    """fastep-launch starts its processes before it has looked for another graph (they import meanwhile): a node
    with FASTEP_LAUNCH_GATE=1 joins DDS only after a line on stdin, and exits 0 without starting on end of input."""
    import rclpy

    from fastep_ros.common import GATE_ENV
    env = {**isolated_env(context.get_domain_id(), tmp_path / 'roslog'), GATE_ENV: '1'}
    node = rclpy.create_node('gate_watcher', context=context)
    cmd = [sys.executable, '-m', 'fastep_ros.clock', '--ros-args', '-r', '__node:=gated_clock']

    def on_graph() -> bool:
        return 'gated_clock' in [name for name, _ in node.get_node_names_and_namespaces()]
    proc = subprocess.Popen(cmd, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        time.sleep(3.0)   # imported by now (0.3 s), and DDS would have shown it (0.1 s)
        assert proc.poll() is None and not on_graph()
        assert proc.stdin is not None
        proc.stdin.write(b'\n')
        proc.stdin.close()
        deadline = time.monotonic() + 20.0
        while not on_graph() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert on_graph()
    finally:
        stop_process(proc)
        node.destroy_node()
    closed = subprocess.run(cmd, env=env, input=b'', capture_output=True, timeout=30)
    assert closed.returncode == 0 and closed.stdout == b'' and closed.stderr == b''


def test_the_launcher_says_what_a_robot_still_waits_for() -> None:
    """Before the goals go out, each missing piece is named (a start that times out says which one)."""
    from fastep_ros.launch import not_ready
    from fastep_ros.monitor import RobotLive

    robot = RobotLive(load_scenario('case_study_1').robots[0])
    names = {'r1', 'r2'}

    def why(goal_readers: int = 2, recorded: dict[str, Any] | None = None, **status: Any) -> str:
        robot.status = {'message': 'idle', 'odom_heard': '3', 'cmd_vel_readers': '2', 'others': 'r2', **status}
        return not_ready('r1', robot, goal_readers, 2, 2, names, {'/r1/odom': 5} if recorded is None else recorded)

    robot.rows = [[0.0, 5.0, 45.0]]
    assert why() == ''
    robot.status = {}
    assert not_ready('r1', robot, 2, 2, 2, names, None) == 'no status from the planner of r1 yet'
    assert why(message='waiting', reason='waiting for the world (/obstacles)') == \
        'the planner of r1 is waiting: waiting for the world (/obstacles)'
    assert why(goal_readers=1) == '/r1/goal_pose has 1 of 2 readers (the planner, fastep-record)'
    assert why(odom_heard='0') == 'the planner of r1 has heard no odometry yet'
    assert why(cmd_vel_readers='1') == '/r1/cmd_vel has 1 of 2 readers (the plant, fastep-clock)'
    assert why(others='') == 'the planner of r1 does not follow r2 yet'
    assert why(recorded={}) == 'fastep-record has not recorded /r1/odom yet'
    robot.rows = []
    assert why() == 'no odometry on /r1/odom heard by fastep-launch yet'


def test_a_wall_time_run_with_many_robots_per_core_spreads_step_plans_over_ticks_unless_told() -> None:
    """16 robots on 2 cores on wall time plan whole steps in 5-7 ms control ticks: the launcher gives their planners
    step_iterations 3 and says so; not in lock step, not over the scenario's own budget or --step-iterations, not for
    planners without FAStep steps, not for few robots."""
    from fastep_core.planning.params import PlannerParams
    from fastep_ros.launch import WALL_STEP_ITERATIONS, step_budget
    paper = PlannerParams()
    budget, note = step_budget(16, 2, False, 'fastep_route', paper)
    assert budget == WALL_STEP_ITERATIONS == 3 and 'step_iterations' in note and '--step-iterations 0' in note
    assert step_budget(16, 2, False, 'fastep_route', paper, given=0) == (0, '')
    assert step_budget(16, 2, False, 'fastep', paper, given=5) == (5, '')
    assert step_budget(16, 2, True, 'fastep_route', paper) == (0, '')
    assert step_budget(16, 2, False, 'fastep_route', PlannerParams(step_iterations=2)) == (2, '')
    assert step_budget(16, 2, False, 'dwa', paper) == (0, '')
    assert step_budget(8, 2, False, 'fastep', paper) == (0, '')


CORRIDOR = """\
name: corridor_head_on
workspace: [0, 0, 40, 20]
obstacles:
  - segment: {start: [15, 11.2], end: [25, 11.2]}
  - segment: {start: [15, 8.8], end: [25, 8.8]}
robots:
  - {name: r1, model: point_mass, start: [4, 10], goal: [36, 10.5], radius: 0.5}
  - {name: r2, model: point_mass, start: [37, 9.5], goal: [3, 10], radius: 0.5}
"""


def test_two_robots_take_turns_in_a_corridor_on_the_graph_exactly_as_in_fastep_sim(tmp_path: Path) -> None:
    """The passage rule (planning/safety/passage.py) on the live graph: each planner names its robot by its namespace,
    as fastep-sim names it, so r2 waits for r1 before the 2.4 m corridor tick for tick as in fastep-sim."""
    scenario = write(tmp_path / 'corridor.yaml', CORRIDOR)
    statuses: dict[str, set[str]] = {}
    reference = simulate(load_scenario(str(scenario)), 'fastep_route', 0,
                         observer=lambda tick: statuses.setdefault(tick.name, set()).add(tick.navigator.reason))
    assert 'waiting for r1 to come through the passage' in statuses['r2']
    out = tmp_path / 'live.json'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    result = run([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--rtf', '50', '--seed', '0',
                  '--algorithm', 'fastep_route', '--json', str(out)], env, timeout=180)
    assert result.returncode == 0, result.stdout + result.stderr
    for robot, sim in zip(json.loads(out.read_text())['runs'][0]['robots'], reference.robots):
        assert robot['reached'] and sim.reached and not robot['collided']
        assert robot['sim_time'] == pytest.approx(sim.sim_time, abs=1e-6)
        assert robot['path_length'] == pytest.approx(sim.path_length, abs=2e-6)


def test_the_report_ends_where_the_recording_has_the_run(monkeypatch: pytest.MonkeyPatch,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    """After the run the launcher waits for fastep-record to take the clock a tick past the run's end, as long as
    its acknowledgements come; the report holds only the rows up to that end (odometry that came in while waiting
    is after it); a recorder that stops acknowledging is waited for END_WAIT and named in one line, unless it has
    taken the run's end itself."""
    import fastep_ros.launch as launch
    from fastep_ros.monitor import RobotLive

    class Graph:
        def __init__(self, acks: bool) -> None:
            self.robots = {'r1': RobotLive(load_scenario('case_study_1').robots[0])}
            self.robots['r1'].rows = [[10.0, 1.0, 2.0]]
            self.recorder_acked, self.clock, self.acks = 9.0, 10.0, acks

        def spin(self, seconds: float) -> None:   # the lock step goes on: a tick of odometry, the recorder behind
            self.clock += 0.05
            self.robots['r1'].rows.append([self.clock, 1.0, 2.0])
            if self.acks:
                self.recorder_acked = self.clock - 0.5

        def running(self, label: str) -> bool:
            return label == 'fastep-record'

    graph = Graph(acks=True)
    launch._await_recording(graph, graph, 10.0, 0.05)   # type: ignore[arg-type]  # a stand-in for both
    assert graph.recorder_acked >= 10.05 - 1e-6
    assert graph.robots['r1'].rows[-1][0] == 10.0 and len(graph.robots['r1'].rows) == 1
    assert capsys.readouterr().err == ''

    monkeypatch.setattr(launch, 'END_WAIT', 0.1)
    stuck = Graph(acks=False)
    launch._await_recording(stuck, stuck, 10.0, 0.05)   # type: ignore[arg-type]  # a stand-in for both
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'the recording may end before the run' in err and '9.00 s of 10.00 s' in err
    assert stuck.robots['r1'].rows[-1][0] == 10.0
    stood = Graph(acks=False)
    stood.recorder_acked = 10.0   # the clock stands at the run's end (a plant that stopped): nothing more comes
    launch._await_recording(stood, stood, 10.0, 0.05)   # type: ignore[arg-type]  # a stand-in for both
    assert capsys.readouterr().err == ''
