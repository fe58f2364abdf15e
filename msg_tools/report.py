"""fastep-report: metrics and the paper's figures from a recorded run (MCAP), live or offline alike.

    fastep-report FILE.mcap [--out DIR] [--radius R]

Why from the recording and not from the simulator: a live run (fastep-launch / fastep-record) has no
simulator object to ask, and offline recordings (fastep-sim --mcap) use the same topics, so one tool reports
both and the numbers can be checked against each other. Everything is measured from the messages:

- path_length: sum of the distances between consecutive `odom` positions (log-time order);
- reached / time_to_goal: the first `status` whose message is `arrived`, its log time minus the robot's first
  `goal_pose` log time (or, without a goal_pose, its first odom);
- min_clearance: smallest distance from an odom position to the surface of an obstacle of the file's
  `/obstacles`, minus the robot radius (negative means it touched); min_robot_gap likewise against the other
  robots, compared at each odom time of either (fastep_core.metrics.trajectory_margins). The radius is, in
  this order: the `fastep` metadata record (fastep-sim and fastep-record with a scenario write it), a
  `robot_radius` value in the robot's status, or --radius (default 0.5); `radius_source` says which;
- activations: the `activations` value of the last status (how often the swarm planned a step), or else the
  number of distinct waypoints.

Writes DIR/report.json and three PNG figures: paths.png (paths among the obstacles with the planned waypoints,
start and goal; Fig. 2/5/8), cost.png (cost over time; Fig. 3/6/9) and velocity.png (the controller's
commands from cmd_vel, or the odometry twist; Fig. 4). Times on the figures are seconds since the first goal.
DIR defaults to <FILE without .mcap>_report next to the file. Exit 0 when the report was written (also from
the recovered part of a truncated file, with a warning line), 2 with one line on stderr when the file cannot
be read or holds no robot.
"""

from __future__ import annotations

import argparse
import json
import math
import struct
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from fastep_core.cli import Parser, fail, guard
from fastep_core.errors import FastepError
from fastep_core.geometry import Obstacle, Obstacles
from fastep_core.metrics import trajectory_margins
from msg_tools.interface import (
    CMD_VEL,
    COST,
    GOAL_POSE,
    MAP,
    METADATA_NAME,
    OBSTACLES,
    ODOM,
    PLAN,
    STATUS,
    TRAILER_POSE,
    TYPES,
    WAYPOINT,
    metadata_key,
    split_robot_topic,
)
from msg_tools.mcap_io import Recording, open_recording

__all__ = ['RecordedRun', 'RobotRecord', 'figures', 'float64_field', 'load_run', 'main', 'metrics',
           'odometry_fields', 'twist_fields', 'write_figures', 'write_report']

DEFAULT_RADIUS = 0.5


@dataclass
class RobotRecord:
    """Time series of one robot, times in seconds of log time."""

    name: str
    model: str = 'point_mass'
    odom: list[tuple[float, float, float]] = field(default_factory=list)           # t, x, y
    odom_twist: list[tuple[float, float, float, float]] = field(default_factory=list)  # t, lin.x, lin.y, ang.z
    cmd: list[tuple[float, float, float, float]] = field(default_factory=list)     # t, lin.x, lin.y, ang.z
    cost: list[tuple[float, float]] = field(default_factory=list)
    waypoints: list[tuple[float, float]] = field(default_factory=list)   # distinct, in order of appearance
    plan: list[tuple[float, float]] = field(default_factory=list)        # the last plan (goal last)
    statuses: list[tuple[float, dict[str, Any]]] = field(default_factory=list)
    goal: tuple[float, float] | None = None
    goal_time: float | None = None
    radius: float | None = None
    radius_source: str = ''


@dataclass
class RecordedRun:
    """What a recording says about a run."""

    path: Path
    robots: dict[str, RobotRecord]
    obstacles: list[Obstacle]
    workspace: tuple[float, float, float, float] | None
    metadata: dict[str, str]
    algorithm: str
    scenario: str
    t0: float
    truncated: bool
    warning: str
    message_count: int


def _robot(robots: dict[str, RobotRecord], name: str) -> RobotRecord:
    if name not in robots:
        robots[name] = RobotRecord(name)
    return robots[name]


# Fast paths for the three high-rate types. rclpy's deserialize_message builds a full Python message (an
# Odometry is ~15 objects and two numpy covariance arrays), which made reading a 10-minute recording take half
# a minute; these read only the needed float64 fields of little-endian CDR (encapsulation 00 01) with struct.
# Alignment is relative to the payload after the 4-byte encapsulation header. Tests compare them with rclpy.
_CDR_LE = b'\x00\x01'
_U32 = struct.Struct('<I')
_ODOM = struct.Struct('<3d4d288x3d3d')  # position, orientation, (pose covariance), twist linear, angular
_TWIST = struct.Struct('<3d3d')
_F64 = struct.Struct('<d')


def _string_end(data: bytes, offset: int) -> int:
    """Offset after a CDR string starting at `offset` (payload offsets; data includes the 4-byte header)."""
    offset = (offset + 3) & ~3
    return offset + 4 + _U32.unpack_from(data, 4 + offset)[0]


def odometry_fields(data: bytes) -> tuple[float, ...] | None:
    """(x, y, qx, qy, qz, qw, linear.x, linear.y, angular.z) of a CDR Odometry, None if not little-endian CDR."""
    if data[:2] != _CDR_LE:
        return None
    offset = _string_end(data, 8)           # header.stamp (8 bytes), header.frame_id
    offset = _string_end(data, offset)      # child_frame_id
    offset = (offset + 7) & ~7
    v = _ODOM.unpack_from(data, 4 + offset)
    return v[0], v[1], v[3], v[4], v[5], v[6], v[7], v[8], v[12]


def twist_fields(data: bytes) -> tuple[float, float, float] | None:
    """(linear.x, linear.y, angular.z) of a CDR Twist."""
    if data[:2] != _CDR_LE:
        return None
    v = _TWIST.unpack_from(data, 4)
    return v[0], v[1], v[5]


def float64_field(data: bytes) -> float | None:
    if data[:2] != _CDR_LE:
        return None
    return _F64.unpack_from(data, 4)[0]


def load_run(recording: Recording) -> RecordedRun:
    """Collect every robot's series, the obstacles and the workspace from a recording."""
    from rclpy.serialization import deserialize_message

    from msg_tools import convert
    from msg_tools.mcap_io import message_class

    robots: dict[str, RobotRecord] = {}
    wanted = [OBSTACLES, MAP]
    kinds: dict[str, tuple[RobotRecord, str]] = {}
    for topic in recording.topics:
        parts = split_robot_topic(topic)
        if parts is not None:
            robot = _robot(robots, parts[0])
            if parts[1] == TRAILER_POSE:
                robot.model = 'tractor_trailer'
            else:
                wanted.append(topic)
                kinds[topic] = (robot, parts[1])
    classes: dict[str, type] = {}

    def decode(type_name: str, data: bytes) -> Any:
        if type_name not in classes:
            classes[type_name] = message_class(type_name)
        try:
            return deserialize_message(data, classes[type_name])
        except Exception as exc:
            raise FastepError(f'{recording.path}: cannot decode a {type_name} message: {exc}') from None

    obstacles: tuple[float, list[Obstacle]] | None = None
    workspace: tuple[float, tuple[float, float, float, float]] | None = None
    waypoints: dict[str, list[tuple[float, tuple[float, float]]]] = {name: [] for name in robots}
    plans: dict[str, tuple[float, list[tuple[float, float]]]] = {}
    goals: dict[str, list[tuple[float, tuple[float, float]]]] = {name: [] for name in robots}
    algorithm = ''
    # File order (fast); every series is sorted by time below.
    for topic, type_name, log_time, _, data, *_ in recording.raw_messages(wanted, log_time_order=False):
        t = log_time * 1e-9
        if topic == OBSTACLES:
            if obstacles is None or t >= obstacles[0]:
                try:
                    obstacles = (t, convert.marker_array_to_obstacles(decode(type_name, data)))
                except ValueError:
                    pass
            continue
        if topic == MAP:
            if workspace is None or t >= workspace[0]:
                try:
                    workspace = (t, convert.occupancy_grid_workspace(decode(type_name, data)))
                except ValueError:
                    pass
            continue
        robot, kind = kinds[topic]
        if kind == ODOM:
            v = odometry_fields(data) if type_name == TYPES[ODOM] else None
            if v is None:
                m = decode(type_name, data)
                p, q, tw = m.pose.pose.position, m.pose.pose.orientation, m.twist.twist
                v = (p.x, p.y, q.x, q.y, q.z, q.w, tw.linear.x, tw.linear.y, tw.angular.z)
            robot.odom.append((t, v[0], v[1]))
            robot.odom_twist.append((t, v[6], v[7], v[8]))
        elif kind == CMD_VEL:
            c = twist_fields(data) if type_name == TYPES[CMD_VEL] else None
            if c is None:
                m = decode(type_name, data)
                tw = m.twist if hasattr(m, 'twist') else m  # TwistStamped or Twist
                c = (tw.linear.x, tw.linear.y, tw.angular.z)
            robot.cmd.append((t, *c))
        elif kind == COST:
            f = float64_field(data) if type_name == TYPES[COST] else None
            robot.cost.append((t, float(decode(type_name, data).data) if f is None else f))
        elif kind == WAYPOINT:
            waypoints[robot.name].append((t, convert.pose_stamped_to_point(decode(type_name, data))))
        elif kind == PLAN:
            if robot.name not in plans or t >= plans[robot.name][0]:
                plans[robot.name] = (t, convert.path_to_waypoints(decode(type_name, data)))
        elif kind == STATUS:
            values = convert.diagnostic_to_dict(decode(type_name, data))
            robot.statuses.append((t, values))
        elif kind == GOAL_POSE:
            goals[robot.name].append((t, convert.pose_stamped_to_point(decode(type_name, data))))
    for robot in robots.values():
        for series in (robot.odom, robot.odom_twist, robot.cmd, robot.cost, robot.statuses):
            series.sort(key=lambda row: row[0])  # stable: equal times keep file order
        for _, point in sorted(waypoints[robot.name], key=lambda row: row[0]):
            if point not in robot.waypoints:
                robot.waypoints.append(point)
        if robot.name in plans:
            robot.plan = plans[robot.name][1]
        if goals[robot.name]:
            first = min(goals[robot.name], key=lambda row: row[0])
            robot.goal_time = first[0]
            robot.goal = max(goals[robot.name], key=lambda row: row[0])[1]
        for _, values in robot.statuses:
            algorithm = values.get('algorithm') or algorithm
    meta = recording.metadata.get(METADATA_NAME, {})
    space = workspace[1] if workspace is not None else None
    if space is None and meta.get('workspace'):
        try:
            corners = [float(v) for v in meta['workspace'].split(',')]
            space = (corners[0], corners[1], corners[2], corners[3]) if len(corners) == 4 else None
        except ValueError:
            space = None
    for robot in robots.values():
        model = meta.get(metadata_key('model', robot.name))
        if model:
            robot.model = model
    starts = [r.goal_time for r in robots.values() if r.goal_time is not None]
    if not starts:
        starts = [r.odom[0][0] for r in robots.values() if r.odom]
    t0 = min(starts) if starts else recording.start_time * 1e-9
    order = [n for n in meta.get('robots', '').split(',') if n in robots]
    ordered = {n: robots[n] for n in order + sorted(n for n in robots if n not in order)}
    return RecordedRun(recording.path, ordered, [] if obstacles is None else obstacles[1], space, meta,
                       meta.get('algorithm', algorithm), meta.get('scenario', ''), t0, recording.truncated,
                       recording.warning(), recording.message_count)


# ----------------------------------------------------------------------------------------------- metrics

def _radius(run: RecordedRun, robot: RobotRecord, default: float) -> tuple[float, str]:
    text = run.metadata.get(metadata_key('radius', robot.name))
    if text:
        try:
            return float(text), 'metadata'
        except ValueError:
            pass
    for _, values in reversed(robot.statuses):
        for key in ('robot_radius', 'radius'):
            if values.get(key):
                try:
                    return float(values[key]), 'status'
                except ValueError:
                    pass
    return default, 'default'


def _int(text: Any) -> int | None:
    try:
        return int(float(text))
    except (TypeError, ValueError):
        return None


def metrics(run: RecordedRun, default_radius: float = DEFAULT_RADIUS) -> dict[str, Any]:
    """The report as a JSON-ready dict (see the module docstring)."""
    for robot in run.robots.values():
        robot.radius, robot.radius_source = _radius(run, robot, default_radius)
    rows = []
    arrays = {name: np.array(r.odom, dtype=float).reshape(-1, 3) for name, r in run.robots.items()}
    kept = trajectory_margins(list(arrays.values()), [float(r.radius or 0.0) for r in run.robots.values()],
                            Obstacles(run.obstacles))
    for k, (name, robot) in enumerate(run.robots.items()):
        odom = arrays[name]
        xy = odom[:, 1:3]
        length = float(np.sqrt((np.diff(xy, axis=0) ** 2).sum(axis=1)).sum()) if len(xy) > 1 else 0.0
        start = robot.goal_time if robot.goal_time is not None else (float(odom[0, 0]) if len(odom) else None)
        arrived = [t for t, s in robot.statuses if s.get('message') == 'arrived' and (start is None or t >= start)]
        reached = bool(arrived)
        time_to_goal = arrived[0] - start if reached and start is not None else None
        # inf: no obstacle in the file, no other robot with odometry, or no odometry of this robot
        clearance = float(kept.obstacles[k]) if math.isfinite(kept.obstacles[k]) else None
        gap = float(kept.robots[k]) if math.isfinite(kept.robots[k]) else None
        last = robot.statuses[-1][1] if robot.statuses else {}
        activations = None
        for _, values in reversed(robot.statuses):
            activations = _int(values.get('activations'))
            if activations is not None:
                break
        source = 'status'
        if activations is None:
            activations, source = len(robot.waypoints), 'waypoints'
        margins = [v for v in (clearance, gap) if v is not None]
        rows.append({
            'name': name, 'model': robot.model, 'reached': reached,
            'collided': bool(margins) and min(margins) < 0.0,
            'path_length': round(length, 6),
            'time_to_goal': None if time_to_goal is None else round(time_to_goal, 6),
            'min_clearance': None if clearance is None else round(clearance, 6),
            'min_robot_gap': None if gap is None else round(gap, 6),
            'radius': robot.radius, 'radius_source': robot.radius_source,
            'activations': activations, 'activations_source': source,
            'waypoints': len(robot.waypoints),
            'final_status': f'{last.get("message", "")}: {last.get("reason", "")}' if last else '',
            'odom_messages': len(robot.odom),
            'goal': None if robot.goal is None else list(robot.goal),
        })
    return {
        'file': str(run.path), 'scenario': run.scenario, 'algorithm': run.algorithm,
        'truncated': run.truncated, 'warning': run.warning, 'messages': run.message_count,
        'obstacles': len(run.obstacles), 'workspace': None if run.workspace is None else list(run.workspace),
        'robots': rows,
    }


# ----------------------------------------------------------------------------------------------- figures

def figures(run: RecordedRun) -> dict[str, Any]:
    """The report's figures (matplotlib Figures, drawn by msg_tools.plots) by file name; times are seconds since
    the first goal."""
    from msg_tools import plots

    text = plots.title(run.scenario or run.path.stem, run.algorithm)
    paths = []
    for robot in run.robots.values():
        odom = np.array(robot.odom, dtype=float).reshape(-1, 3)
        length = float(np.sqrt((np.diff(odom[:, 1:3], axis=0) ** 2).sum(axis=1)).sum())
        start = (float(odom[0, 1]), float(odom[0, 2])) if len(odom) else None
        waypoints = robot.plan[:-1] if robot.plan else robot.waypoints   # the plan's last pose is the goal
        paths.append(plots.RobotPath(robot.name, odom[:, 1:3], length, np.array(waypoints, dtype=float).reshape(-1, 2),
                                     start, robot.goal))
    costs = {robot.name: np.array(robot.cost, dtype=float).reshape(-1, 2) - [run.t0, 0.0]
             for robot in run.robots.values()}
    velocities = []
    for robot in run.robots.values():
        source, series = ('cmd_vel', robot.cmd) if robot.cmd else ('odom', robot.odom_twist)
        velocities.append(plots.Velocities(robot.name, source, robot.model,
                                           np.array(series, dtype=float).reshape(-1, 4) - [run.t0, 0.0, 0.0, 0.0]))
    return {'paths.png': plots.paths_figure(run.obstacles, run.workspace, paths, text),
            'cost.png': plots.cost_figure(costs, text),
            'velocity.png': plots.velocity_figure(velocities, text)}


def write_figures(run: RecordedRun, out: Path) -> list[Path]:
    """paths.png, cost.png and velocity.png in out; returns their paths."""
    from msg_tools.plots import save

    return [save(fig, out / name) for name, fig in figures(run).items()]


def write_report(path: str | Path, out: str | Path | None = None, radius: float = DEFAULT_RADIUS,
                 figures: bool = True) -> tuple[dict[str, Any], list[Path]]:
    """Read a recording, write out/report.json (and the figures); return the report and the files written."""
    recording = open_recording(path)
    run = load_run(recording)
    if not run.robots:
        raise FastepError(f'{recording.path} holds no robot topics (/<name>/odom, status, ...): nothing to report')
    report = metrics(run, radius)
    folder = Path(out) if out is not None else recording.path.with_name(recording.path.stem + '_report')
    folder.mkdir(parents=True, exist_ok=True)
    files = [folder / 'report.json']
    files[0].write_text(json.dumps(report, indent=1) + '\n')
    if figures:
        files += write_figures(run, folder)
    return report, files


# ----------------------------------------------------------------------------------------------- CLI

PROG = 'fastep-report'


def _parser() -> argparse.ArgumentParser:
    p = Parser(prog=PROG, description='Metrics and figures of a recorded run (MCAP).')
    p.add_argument('file', type=Path, help='MCAP recording (fastep-record or fastep-sim --mcap)')
    p.add_argument('--out', type=Path, metavar='DIR', help='output folder (default: <file>_report next to it)')
    p.add_argument('--radius', type=float, default=DEFAULT_RADIUS,
                   help='robot radius when the file does not say (default 0.5 m)')
    p.add_argument('--no-figures', action='store_true', help='write report.json only')
    return p


def _line(row: dict[str, Any]) -> str:
    state = 'arrived' if row['reached'] else 'NOT arrived'
    when = f'{row["time_to_goal"]:.1f} s' if row['time_to_goal'] is not None else '-'
    clear = f'{row["min_clearance"]:.2f} m' if row['min_clearance'] is not None else '-'
    return (f'{row["name"]}: {state}{" COLLIDED" if row["collided"] else ""}, path {row["path_length"]:.2f} m, '
            f'time {when}, min clearance {clear}, activations {row["activations"]}')


def main(argv: Sequence[str] | None = None) -> int:
    return guard(PROG, lambda: _run(argv))


def _run(argv: Sequence[str] | None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if not (math.isfinite(args.radius) and args.radius >= 0.0):
        parser.error(f'--radius must be a finite number >= 0, got {args.radius}')
    try:  # a FastepError (unreadable recording, no robot in it) is guard's one line
        report, files = write_report(args.file, args.out, args.radius, figures=not args.no_figures)
    except OSError as exc:
        return fail(PROG, f'cannot write the report: {exc}')
    if report['warning']:
        print(f'{PROG}: warning: {report["warning"]}', file=sys.stderr)
    for row in report['robots']:
        print(_line(row))
    print('wrote ' + ', '.join(str(f) for f in files))
    return 0


if __name__ == '__main__':
    sys.exit(main())
