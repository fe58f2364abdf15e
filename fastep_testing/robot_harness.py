"""The robot harness: the planner node driving a simulated base on wall time, as on a robot, and what it measures.

    python -m fastep_testing.robot_harness run open_room [--no-laser] [--json out.json]
    python -m fastep_testing.robot_harness base --ros-args -p scenario:=world.yaml ...   (the base alone)

run_world starts two processes on an isolated DDS domain (fastep_testing.graph): the base (robot_base: odometry
at 50 Hz, a 720-beam 270-degree laser at 20 Hz, a latched /map of what the planner may know) and fastep-planner
(obstacle_source map, diff_drive), no clock and no lock step. It sends the goal once the planner is `idle`, waits
for `arrived` or `failed` on `status` (or the timeout), stops both by pid, and judges the run from the base's
record (robot_measures): arrival, collision and clearance against the TRUE world, cmd_vel gaps, accelerations at
the base (between successive commands and over SPAN of them), the planner's control_ms (the largest p99 and
max its status gave during the run) and its CPU share (/proc/<pid>/stat) from the goal to the end.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import yaml

from fastep_core.dynamic_world import DynamicWorld
from fastep_core.dynamics import PRESETS, preset
from fastep_core.metrics import trajectory_margins
from fastep_core.scenario import Scenario, scenario_data
from fastep_testing import robot_measures as measures
from fastep_testing.graph import Helper, free_domain, isolated_env, stop_process
from fastep_testing.robot_worlds import world as harness_world

__all__ = ['CONTROL_PERIOD', 'HarnessResult', 'judge', 'main', 'run_world']

CONTROL_PERIOD = 0.05   # s: the planner's default control_rate_hz, 20
GAP = 0.15              # s: a gap the table counts besides 2 control periods
DONE = ('arrived', 'failed')
SPAN = 5              # commands the mean accelerations span (0.25 s at 20 Hz)
TAIL = 0.5            # s: commands taken after the end of a run still count (the stop at arrival)
RESEND = 5.0          # s: the goal is sent again while the planner stays idle this long after it


@dataclass
class HarnessResult:
    """One run (module docstring). Times in s, speeds in m/s, CPU in percent of one core; NaN: not measured."""

    world: str
    laser: bool
    arrived: bool = False
    status: str = ''                  # the planner's last status message, and its reason
    reason: str = ''
    time_to_goal: float = math.nan    # goal sent -> `arrived` heard
    collided: bool = False            # the base's true track came within the radius of a true obstacle
    min_clearance: float = math.nan   # m, against the truth (negative: a collision)
    final_distance: float = math.nan  # m, the base's true position at the end to the goal
    arrival_speed: float = math.nan   # m/s, the base's true speed when `arrived` was heard
    arrival_turn_rate: float = math.nan   # rad/s, likewise
    dynamics: str = ''                # the physics base's preset ('' kinematic)
    commands: int = 0                 # cmd_vel messages taken by the base during the run
    gaps_over_015: int = 0
    gaps_over_2_periods: int = 0
    longest_gap: float = math.nan
    max_dv_dt: float = math.nan       # between successive commands at the base
    max_domega_dt: float = math.nan
    mean_dv_dt: float = math.nan      # the same over SPAN successive commands (robot_measures)
    mean_domega_dt: float = math.nan
    control_p99_ms: float = math.nan  # the largest p99 / max the planner's status gave during the run
    control_max_ms: float = math.nan
    control_cpu_p99_ms: float = math.nan
    planner_cpu: float = math.nan     # % of a core, goal sent -> end
    base_cpu: float = math.nan
    scans: int = 0                    # scans the planner took (its status)
    laser_mount: tuple[float, float, float] = (0.0, 0.0, 0.0)
    phantom_movers: int = 0           # distinct tracks the planner called movers (every harness world is still)
    most_movers: int = 0              # the most it called movers at once
    phantom_obstacles: int = 0        # the most still obstacles it believed from its scans where the truth has none
    planner_rss_mb: float = math.nan       # the planner's resident memory when the goal was sent
    planner_peak_rss_mb: float = math.nan  # its peak resident memory (VmHWM) at the end of the run
    most_late: float = 0.0            # s: the most lateness the planner's status gave (planning/safety/lateness.py)
    slowed: int = 0                   # statuses that said the speed was reduced for it
    load: tuple[float, float, float] = (0.0, 0.0, 0.0)   # os.getloadavg() at the start
    log_dir: str = ''
    notes: list[str] = field(default_factory=list)


def _planner_command() -> list[str]:
    script = Path(sys.executable).with_name('fastep-planner')
    return [str(script)] if script.exists() else [sys.executable, '-m', 'fastep_ros.planner']


def _start(cmd: list[str], env: dict[str, str], log: Path) -> subprocess.Popen[bytes]:
    with open(log, 'wb') as out:
        return subprocess.Popen(cmd, env=env, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)


def _cpu(pid: int) -> float:
    try:
        return measures.process_cpu_seconds(pid)
    except OSError:
        return math.nan


def run_world(scenario: Scenario | str, *, laser: bool = True, timeout: float = 90.0, start_timeout: float = 60.0,
              max_speed: float = 1.0, seed: int = 0, algorithm: str = '', log_dir: Path | None = None,
              laser_mount: tuple[float, float, float] = (0.0, 0.0, 0.0), dynamics: str = '', laser_frame: str = '',
              laser_tf: bool = True, planner_params: dict[str, Any] | None = None,
              attacker: Sequence[str] | None = None) -> HarnessResult:
    """One run of a harness world (a robot_worlds name or a Scenario with one diff-drive robot); see the module
    docstring. Every process it starts is stopped before it returns. Logs go to log_dir (default: a temporary
    folder, removed). laser_mount: where the laser sits on the base (x, y, yaw); the planner is told it
    (parameter laser_mount) when it is off the centre. dynamics: a physics base of that preset
    (fastep_core/dynamics) in place of the robot's own (the kinematic one, unless the scenario gives dynamics).
    laser_frame: the base scans in this frame and publishes base_link -> it on /tf_static (unless not laser_tf),
    and the planner is not told laser_mount: it takes the mount from TF, as on a ROS robot (without the transform
    it is never `idle` with scans: the goal is sent once it is `blind`). planner_params: more of the planner's
    parameters (name: value as `-p name:=value` takes it). attacker: a command started beside the two on the
    same domain (benchmarks.hostile_inputs: a neighbour sending what it should not), stopped first at the end."""
    scenario = harness_world(scenario) if isinstance(scenario, str) else scenario
    if dynamics:
        scenario = replace(scenario, robots=(replace(scenario.robots[0], dynamics=preset(dynamics)),
                                             *scenario.robots[1:]))
    if log_dir is None:
        with tempfile.TemporaryDirectory(prefix='fastep-harness-') as tmp:
            result = run_world(scenario, laser=laser, timeout=timeout, start_timeout=start_timeout,
                               max_speed=max_speed, seed=seed, algorithm=algorithm, log_dir=Path(tmp),
                               laser_mount=laser_mount, laser_frame=laser_frame,
                               laser_tf=laser_tf, planner_params=planner_params, attacker=attacker)
            result.log_dir = ''
            return result
    log_dir.mkdir(parents=True, exist_ok=True)
    robot = scenario.robots[0]
    mount = tuple(float(v) for v in laser_mount)
    result = HarnessResult(scenario.name, laser, load=os.getloadavg(), log_dir=str(log_dir),
                           laser_mount=(mount[0], mount[1], mount[2]),
                           dynamics='' if robot.dynamics is None else robot.dynamics.preset)
    world_file, record = log_dir / 'world.yaml', log_dir / 'base.npz'
    world_file.write_text(yaml.safe_dump(scenario_data(scenario)))
    record.unlink(missing_ok=True)
    domain = free_domain()
    env = isolated_env(domain, log_dir / 'roslog')
    env['FASTEP_PARENT_PID'] = str(os.getpid())   # fastep_ros.common: a node gets SIGINT if this process dies
    ros = ['--ros-args', '--log-level', os.environ.get('FASTEP_TEST_LOG_LEVEL', 'warn')]
    base_cmd = [sys.executable, '-m', 'fastep_testing.robot_harness', 'base', *ros, '-p',
                f'scenario:={world_file}', '-p', f'record:={record}', '-p', f'seed:={seed}',
                '-p', f'scan_rate_hz:={20.0 if laser else 0.0}', '-p', f'laser_mount:={list(mount)!r}'] + \
        (['-p', f'laser_frame:={laser_frame}', '-p', f'laser_tf:={str(laser_tf).lower()}'] if laser_frame else [])
    planner_cmd = [*_planner_command(), *ros, '-p', 'obstacle_source:=map', '-p', 'model:=diff_drive',
                   '-p', f'robot_radius:={robot.radius!r}', '-p', f'max_speed:={float(max_speed)!r}',
                   '-p', f'seed:={seed}'] + (['-p', f'algorithm:={algorithm}'] if algorithm else []) + \
                  (['-p', f'laser_mount:={list(mount)!r}'] if any(mount) and not laser_frame else []) + \
                  [arg for name, value in (planner_params or {}).items() for arg in ('-p', f'{name}:={value}')]
    procs: dict[str, subprocess.Popen[bytes]] = {}
    helper: Helper | None = None
    statuses: list[tuple[float, dict[str, Any]]] = []
    beliefs: list[tuple[float, Any]] = []
    window = (math.nan, math.nan)
    cpu: dict[str, tuple[float, float]] = {}
    try:
        procs['base'] = _start(base_cmd, env, log_dir / 'base.log')
        procs['planner'] = _start(planner_cmd, env, log_dir / 'planner.log')
        if attacker:
            procs['attacker'] = _start(list(attacker), env, log_dir / 'attacker.log')
        helper = _status_helper(domain, statuses, beliefs)
        placed = not laser_frame or laser_tf   # the planner can use its scans
        helper.spin_until(lambda: _ready(statuses, laser, placed) or _dead(procs), start_timeout,
                          lambda: f'the planner to be idle with odometry (last status: {_last(statuses) or "none"})')
        if _dead(procs):
            raise RuntimeError(f'a process ended at the start: {_exits(procs)}')
        send_goal = _goal_sender(helper, robot.goal, start_timeout, lambda: _last(statuses) == 'idle')
        began = time.monotonic()
        before = {name: _cpu(p.pid) for name, p in procs.items()}
        result.planner_rss_mb = _memory_mb(procs['planner'].pid, 'VmRSS')
        try:
            helper.spin_until(lambda: send_goal() and _last(statuses, after=began) in DONE or _dead(procs), timeout,
                              'the goal')
        except AssertionError:
            result.notes.append(f'timed out after {timeout:g} s')
        end = time.monotonic()
        after = {name: _cpu(p.pid) for name, p in procs.items()}
        result.planner_peak_rss_mb = _memory_mb(procs['planner'].pid, 'VmHWM')
        helper.spin_for(TAIL)   # the command that stops the robot at its arrival comes after the status
        if _dead(procs):
            result.notes.append(f'a process ended during the run: {_exits(procs)}')
        window = (began, end)
        cpu = {name: (before[name], after[name]) for name in procs}
    except (AssertionError, RuntimeError) as exc:
        result.notes.append(str(exc))
    finally:
        if helper is not None:
            helper.close()
        for name in ('attacker', 'planner', 'base'):   # the planner before the base: it records until stopped
            if name in procs:
                stop_process(procs[name])
    if record.exists() and not math.isnan(window[0]):
        with np.load(record) as data:
            judge(result, scenario, data['commands'], data['track'], statuses, window, cpu)
        count_phantoms(result, scenario, [m for t, m in beliefs if window[0] <= t <= window[1]])
    elif not result.notes:
        result.notes.append('the base wrote no record')
    return result


def _status_helper(domain: int, statuses: list[tuple[float, dict[str, Any]]],
                   beliefs: list[tuple[float, Any]]) -> Helper:
    from diagnostic_msgs.msg import DiagnosticStatus
    from visualization_msgs.msg import MarkerArray

    from msg_tools.convert import diagnostic_to_dict
    from msg_tools.interface import LATEST, STATUS, STATUS_QOS, TRACKED_OBSTACLES
    helper = Helper(domain)
    helper.node.create_subscription(DiagnosticStatus, '/' + STATUS,
                                    lambda msg: statuses.append((time.monotonic(), diagnostic_to_dict(msg))),
                                    STATUS_QOS)
    helper.node.create_subscription(MarkerArray, '/' + TRACKED_OBSTACLES,
                                    lambda msg: beliefs.append((time.monotonic(), msg)),
                                    LATEST)
    return helper


def _goal_sender(helper: Helper, goal: tuple[float, float], timeout: float,
                 idle: Callable[[], bool]) -> Callable[[], bool]:
    """Send the goal, latched (the planner's subscription catches up with a latched publisher it matched late:
    fastep_ros.goals), once the planner's goal subscription is matched; the function returned sends it again
    every RESEND s while `idle()` (the planner's last status is still idle), and returns True."""
    from geometry_msgs.msg import PoseStamped

    from msg_tools.convert import point_to_pose_stamped
    from msg_tools.interface import GOAL_POSE, LATCHED
    pub = helper.node.create_publisher(PoseStamped, '/' + GOAL_POSE, LATCHED)
    helper.spin_until(lambda: pub.get_subscription_count() > 0, timeout, 'the planner\'s goal subscription')
    sent = [time.monotonic()]
    pub.publish(point_to_pose_stamped(goal))

    def again() -> bool:
        if time.monotonic() - sent[-1] > RESEND and idle():
            sent.append(time.monotonic())
            pub.publish(point_to_pose_stamped(goal))
        return True
    return again


def _memory_mb(pid: int, field: str) -> float:
    """VmRSS / VmHWM of a process in MB (/proc/<pid>/status); NaN when it cannot be read."""
    try:
        for line in Path(f'/proc/{pid}/status').read_text().splitlines():
            if line.startswith(field + ':'):
                return int(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return math.nan


def _ready(statuses: list[tuple[float, dict[str, Any]]], laser: bool, placed: bool = True) -> bool:
    """The planner is idle, has the world and has heard odometry (and scans, with the laser); with scans it cannot
    place, blind (and has heard odometry)."""
    if not placed:
        return _last(statuses) == 'blind' and _count(statuses[-1][1], 'odom_heard') > 0
    if _last(statuses) != 'idle':
        return False
    status = statuses[-1][1]
    return _count(status, 'odom_heard') > 0 and (not laser or _count(status, 'scans') > 0)


def _number(value: Any) -> float:
    try:
        return float(value or 0.0)
    except (TypeError, ValueError):
        return 0.0


def _count(status: dict[str, Any], key: str) -> int:
    try:
        return int(status.get(key, 0) or 0)
    except ValueError:
        return 0


def _last(statuses: list[tuple[float, dict[str, Any]]], after: float = -math.inf) -> str:
    return str(statuses[-1][1].get('message', '')) if statuses and statuses[-1][0] >= after else ''


def _dead(procs: dict[str, subprocess.Popen[bytes]]) -> bool:
    """The base or the planner has ended (an attacker may end when its attack is done)."""
    return any(p.poll() is not None for name, p in procs.items() if name != 'attacker')


def _exits(procs: dict[str, subprocess.Popen[bytes]]) -> str:
    return ', '.join(f'{name} exit {p.poll()}' for name, p in procs.items() if p.poll() is not None)


def judge(result: HarnessResult, scenario: Scenario, commands: np.ndarray, track: np.ndarray,
          statuses: Sequence[tuple[float, dict[str, Any]]], window: tuple[float, float],
          cpu: dict[str, tuple[float, float]]) -> HarnessResult:
    """Fill `result` from the base's record (commands rows (arrival, v, omega); track rows (t, x, y, theta, v,
    omega), steady seconds), the statuses heard (steady time, status dict), the run's window (goal sent, end:
    commands up to TAIL after it count) and CPU seconds of each process at its ends."""
    began, end = window
    robot = scenario.robots[0]
    during = [s for t, s in statuses if began <= t <= end]
    final = during[-1] if during else (statuses[-1][1] if statuses else {})
    result.status, result.reason = str(final.get('message', '')), str(final.get('reason', ''))
    arrived_at = next((t for t, s in statuses if t >= began and s.get('message') == 'arrived'), None)
    result.arrived = arrived_at is not None
    result.time_to_goal = arrived_at - began if arrived_at is not None else math.nan
    truth = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs)
    margins = trajectory_margins([track[:, :3]], [robot.radius], truth.still.obstacles, truth.movers)
    result.min_clearance = float(margins.overall[0])
    result.collided = result.min_clearance < 0.0
    result.final_distance = float(math.hypot(track[-1, 1] - robot.goal[0], track[-1, 2] - robot.goal[1]))
    if arrived_at is not None:
        row = track[max(int(np.searchsorted(track[:, 0], arrived_at)) - 1, 0)]
        result.arrival_speed, result.arrival_turn_rate = abs(float(row[4])), abs(float(row[5]))
    run = commands[(commands[:, 0] >= began) & (commands[:, 0] <= end + TAIL)]
    result.commands = len(run)
    # A silence at either end of the run counts too.
    times = np.concatenate([[began], run[:, 0], [max(end, run[-1, 0]) if len(run) else end]])
    result.gaps_over_015 = measures.command_gaps(times, GAP).count
    gaps = measures.command_gaps(times, 2.0 * CONTROL_PERIOD)
    result.gaps_over_2_periods, result.longest_gap = gaps.count, gaps.longest
    result.max_dv_dt, result.max_domega_dt = measures.command_accelerations(run[:, 0], run[:, 1], run[:, 2])
    result.mean_dv_dt, result.mean_domega_dt = measures.command_accelerations(run[:, 0], run[:, 1], run[:, 2],
                                                                               span=SPAN)
    result.most_late = max((_number(s.get('late')) for s in during), default=0.0)
    result.slowed = sum('speed reduced' in str(s.get('reason', '')) for s in during)
    wall = [measures.parse_control_ms(str(s.get('control_ms', ''))) for s in during]
    cpu_ms = [measures.parse_control_ms(str(s.get('control_cpu_ms', ''))) for s in during]
    walls = [w for w in wall if w is not None]
    cpus = [c for c in cpu_ms if c is not None]
    if walls:
        result.control_p99_ms = max(w[1] for w in walls)
        result.control_max_ms = max(w[2] for w in walls)
    if cpus:
        result.control_cpu_p99_ms = max(c[1] for c in cpus)
    if 'planner' in cpu:
        result.planner_cpu = measures.cpu_percent(*cpu['planner'], end - began)
    if 'base' in cpu:
        result.base_cpu = measures.cpu_percent(*cpu['base'], end - began)
    result.scans = _count(final, 'scans')
    return result


PHANTOM_REACH = 0.3   # m: a believed surface farther than this from every true one is a phantom


def count_phantoms(result: HarnessResult, scenario: Scenario, beliefs: Sequence[Any]) -> HarnessResult:
    """Fill the phantom counts from the planner's tracked_obstacles (visualization_msgs/MarkerArray, as
    msg_tools.convert.belief_to_marker_array draws a Belief) heard during the run: every harness world is still,
    so each track called a mover is a phantom, and so is each seen circle or wall piece not within PHANTOM_REACH
    of a true surface (a circle: its nearest point; a wall piece: both ends and its middle)."""
    from msg_tools.convert import CIRCLES_NS, SEGMENTS_NS, TRACKS_NS
    truth = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs).still.obstacles
    names: set[str] = set()
    for msg in beliefs:
        movers = [m.text for m in msg.markers if m.ns == TRACKS_NS]
        names.update(movers)
        result.most_movers = max(result.most_movers, len(movers))
        phantoms = 0
        for m in msg.markers:
            if m.ns == f'seen_{CIRCLES_NS}':
                gap = truth.clearance(np.array([[m.pose.position.x, m.pose.position.y]])) - 0.5 * m.scale.x
                phantoms += int(gap[0] > PHANTOM_REACH)
            elif m.ns == f'seen_{SEGMENTS_NS}' and m.points:
                ends = np.array([[p.x, p.y] for p in m.points]).reshape(-1, 2, 2)
                samples = np.concatenate([ends, ends.mean(axis=1, keepdims=True)], axis=1).reshape(-1, 2)
                far = ~truth.near(samples, PHANTOM_REACH)
                phantoms += int(far.reshape(-1, 3).any(axis=1).sum())
        result.phantom_obstacles = max(result.phantom_obstacles, phantoms)
    result.phantom_movers = len(names)
    return result


# ----------------------------------------------------------------------------------------------- command line

def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] == ['base']:
        from fastep_testing.robot_base import main as base_main
        return base_main(['robot-base', *args[1:]])
    parser = argparse.ArgumentParser(prog='python -m fastep_testing.robot_harness', description=__doc__.split('\n')[0])
    sub = parser.add_subparsers(dest='command', required=True)
    sub.add_parser('base', help='the simulated base alone (ROS arguments follow)')
    run = sub.add_parser('run', help='one run of a harness world')
    run.add_argument('world', help='a world of fastep_testing/robot_worlds.py')
    run.add_argument('--no-laser', action='store_true', help='the base publishes no scan')
    run.add_argument('--timeout', type=float, default=90.0, help='seconds from the goal to give up')
    run.add_argument('--algorithm', default='', help='the planner\'s algorithm (default: its own)')
    run.add_argument('--log-dir', type=Path, help='keep the processes\' logs and the base\'s record here')
    run.add_argument('--json', type=Path, help='write the result here')
    run.add_argument('--laser-mount', type=float, nargs=3, default=(0.0, 0.0, 0.0), metavar=('X', 'Y', 'YAW'),
                     help='where the laser sits on the base (m, m, rad)')
    run.add_argument('--dynamics', default='', choices=('', *PRESETS),
                     help='a physics base of this preset (fastep_core/dynamics) in place of the kinematic one')
    options = parser.parse_args(args)
    result = run_world(options.world, laser=not options.no_laser, timeout=options.timeout,
                       algorithm=options.algorithm, log_dir=options.log_dir, laser_mount=tuple(options.laser_mount),
                       dynamics=options.dynamics)
    text = json.dumps(asdict(result), indent=1)
    print(text)
    if options.json:
        options.json.write_text(text + '\n')
    return 0 if result.arrived and not result.collided else 1


if __name__ == '__main__':
    raise SystemExit(main())
