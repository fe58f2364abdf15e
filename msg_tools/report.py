"""fastep-report: metrics and the paper's figures from a recorded run (MCAP), live or offline alike.

    fastep-report FILE.mcap [--out DIR] [--radius R]

Why from the recording: a live run has no simulator object to ask, and offline recordings (fastep-sim --mcap) use
the same topics, so one tool reports both and the numbers can be checked against each other. Per robot: path_length
(odom positions in log-time order; null when no odometry decoded), reached and time_to_goal (the first `arrived`
status, from its `since` value or log time, minus the first goal_pose or odom), min_clearance (to the surfaces of
/obstacles, or of a v2 run's true world in its metadata, minus the radius: negative means touched), min_robot_gap,
activations (the last status' value, else distinct waypoints). Radius: the `fastep` metadata, a status'
robot_radius, or --radius (`radius_source` says which). A true world beyond the scenario file limits or invalid is
ignored with a warning; distances are taken JUDGE_ELEMENTS pairs at a time so memory stays bounded. Writes
DIR/report.json, paths.png (Fig. 2/5/8), cost.png (Fig. 3/6/9), velocity.png (Fig. 4); DIR defaults to
<FILE without .mcap>_report. Exit 0 (also from a truncated file, with a warning), 2 with one line on bad input.
The recording is read by msg_tools/recorded_run.py.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.cli import Parser, fail, guard
from fastep_core.dynamic_world import Movers, ObstacleSpec
from fastep_core.errors import FastepError
from fastep_core.footprint import Footprint
from fastep_core.geometry import Circle, Obstacles
from fastep_core.metrics import Margins, mover_clearance, obstacle_clearance, trajectory_margins
from msg_tools.cdr import float64_field, odometry_fields, twist_fields
from msg_tools.interface import SCENARIO_DATA, metadata_key
from msg_tools.mcap_io import open_recording
from msg_tools.recorded_run import MAX_COORDINATE, RecordedRun, RobotRecord, began, load_run, read_scenario_data

__all__ = ['RecordedRun', 'RobotRecord', 'figures', 'float64_field', 'judge', 'load_run', 'main', 'metrics',
           'odometry_fields', 'read_scenario_data', 'twist_fields', 'write_figures', 'write_report']

DEFAULT_RADIUS = 0.5
FloatArray = NDArray[np.float64]
JUDGE_ELEMENTS = 1 << 20
"""(odometry sample, obstacle) and (odometry sample, mover segment) pairs measured in one numpy step: a few
arrays of this many float64 (8 MiB each) at a time, whatever the numbers of samples and obstacles. Measured all
at once, 2,000 samples against 60,000 movers took 4.9 GB (MemoryError under a 1.5 GB cap)."""


# ----------------------------------------------------------------------------------------------- metrics

def _radius_value(text: Any) -> float | None:
    try:
        value = float(text)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) and 0.0 <= value <= MAX_COORDINATE else None


def _radius(run: RecordedRun, robot: RobotRecord, default: float) -> tuple[float, str, str]:
    """(radius, where it came from, a problem with a source passed over or '')."""
    problem = ''
    text = run.metadata.get(metadata_key('radius', robot.name))
    if text:
        value = _radius_value(text)
        if value is not None:
            return value, 'metadata', ''
        problem = f'{metadata_key("radius", robot.name)} = {text[:40]!r} in the metadata is not a radius: left out'
    for _, values in reversed(robot.statuses):
        for key in ('robot_radius', 'radius'):
            if values.get(key):
                value = _radius_value(values[key])
                if value is not None:
                    return value, 'status', problem
    return default, 'default', problem


def _footprint(run: RecordedRun, name: str) -> tuple[Footprint | None, str]:
    """The robot's outline from the metadata (None: a disc), and a problem with it or ''."""
    key = metadata_key('footprint', name)
    text = run.metadata.get(key)
    if not text:
        return None, ''
    try:
        return Footprint.parse(text, what=key), ''
    except ValueError as exc:
        return None, f'{exc}: judged as a disc'


def _int(text: Any) -> int | None:
    try:
        return int(float(text))
    except (TypeError, ValueError, OverflowError):
        return None


def _json_ready(value: Any) -> Any:
    """value with every float that is not finite as None (null): JSON has no NaN or Infinity."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_ready(v) for v in value]
    return value


def _mover_groups(specs: Sequence[ObstacleSpec]) -> list[Movers]:
    """The movers among specs as Movers, in groups of at most JUDGE_ELEMENTS vertices: Movers pads every
    polyline to the longest, so one mover with 50,000 waypoints among 6,000 would make a 6,000 x 50,000 array."""
    moving = sorted((s for s in specs if s.motion is not None and isinstance(s.shape, Circle)),
                    key=lambda s: len(s.motion.waypoints) if s.motion is not None else 0)
    groups: list[Movers] = []
    start = 0
    while start < len(moving):
        end = start + 1   # sorted by length: the last of a group is its longest
        while end < len(moving) and (end + 1 - start) * _vertices(moving[end]) <= JUDGE_ELEMENTS:
            end += 1
        part = moving[start:end]
        groups.append(Movers([s.shape for s in part if isinstance(s.shape, Circle)],
                             [s.motion for s in part if s.motion is not None]))
        start = end
    return groups


def _vertices(spec: ObstacleSpec) -> int:
    return 1 + (len(spec.motion.waypoints) if spec.motion is not None else 0)


def _mover_chunk(movers: Movers) -> int:
    """Samples per step so that a step measures at most JUDGE_ELEMENTS (sample, mover segment) pairs."""
    return max(1, JUDGE_ELEMENTS // (len(movers) * max(1, movers.vertices.shape[1] - 1)))


def judge(tracks: Sequence[FloatArray], radii: Sequence[float], obstacles: Obstacles,
          specs: Sequence[ObstacleSpec] = (), outlines: Sequence[tuple[Footprint, FloatArray] | None] = ()) -> Margins:
    """fastep_core.metrics.trajectory_margins(tracks, radii, obstacles, movers of specs), the same numbers, in
    bounded memory: obstacles and movers are measured against at most JUDGE_ELEMENTS pairs at a time (that
    function holds 16,384 samples x every obstacle or mover at once). outlines[i]: robot i's footprint and the
    heading of each of its samples, judged against the still obstacles in place of its disc (movers: its disc)."""
    kept = trajectory_margins(tracks, radii, Obstacles(), None)   # robot against robot: linear in the samples
    groups = _mover_groups(specs)
    to_obstacles = kept.obstacles.copy()
    for i, track in enumerate(tracks):
        rows = np.asarray(track, dtype=float).reshape(len(track), -1) if len(track) else np.zeros((0, 3))
        if not len(rows):
            continue
        outline = outlines[i] if i < len(outlines) else None
        if len(obstacles) and outline is not None:
            footprint, headings = outline
            to_obstacles[i] = float(footprint.clearance(np.column_stack([rows[:, 1:3], headings]), obstacles).min())
        elif len(obstacles):
            chunk = max(1, JUDGE_ELEMENTS // len(obstacles))
            to_obstacles[i] = obstacle_clearance(obstacles, rows[:, 1:3], chunk) - radii[i]
        for movers in groups:
            to_obstacles[i] = min(to_obstacles[i], mover_clearance(movers, rows, _mover_chunk(movers)) - radii[i])
    return Margins(to_obstacles, kept.robots)


def metrics(run: RecordedRun, default_radius: float = DEFAULT_RADIUS) -> dict[str, Any]:
    """The report as a JSON-ready dict (see the module docstring)."""
    notes = []
    for robot in run.robots.values():
        robot.radius, robot.radius_source, problem = _radius(run, robot, default_radius)
        if problem:
            notes.append(problem)
    rows = []
    arrays = {name: np.array(r.odom, dtype=float).reshape(-1, 3) for name, r in run.robots.items()}
    truth, why = run.read_truth()
    if why:
        notes.append(f'{SCENARIO_DATA} in the metadata ignored (the run is judged against its /obstacles), it is '
                     f'not a scenario: {why}')
    tracks = list(arrays.values())
    specs: Sequence[ObstacleSpec] = ()
    if truth is None:
        obstacles = Obstacles(run.obstacles)
    else:
        # A v2 world: judged against the truth over time. The movers are placed at each odometry's own stamp
        # (the run's simulated seconds): the recorder's receive time lags it by a tick or more under lock step,
        # and a mover at 0.5 m/s moves 9 cm in 0.17 s.
        obstacles, specs = truth.world.obstacles, truth.obstacle_specs   # the world: every still obstacle
        tracks = [np.array(r.odom_stamped, dtype=float).reshape(-1, 3) for r in run.robots.values()]
    # A robot the scenario gives a footprint is judged by its outline at each odometry's heading.
    outlines: list[tuple[Footprint, FloatArray] | None] = []
    for name, robot in run.robots.items():
        footprint, problem = _footprint(run, name)
        if problem:
            notes.append(problem)
        outlines.append((footprint, np.array(robot.yaw, dtype=float))
                        if footprint is not None and len(robot.yaw) == len(robot.odom) else None)
    kept = judge(tracks, [float(r.radius or 0.0) for r in run.robots.values()], obstacles, specs, outlines)
    for k, (name, robot) in enumerate(run.robots.items()):
        odom = arrays[name]
        xy = odom[:, 1:3]
        # None: no odometry of it decoded, so no path to measure (0 m would say it stood still)
        length = float(np.sqrt((np.diff(xy, axis=0) ** 2).sum(axis=1)).sum()) if len(xy) else None
        start = robot.goal_time if robot.goal_time is not None else (float(odom[0, 0]) if len(odom) else None)
        arrived = [began(t, s, start) for t, s in robot.statuses
                   if s.get('message') == 'arrived' and (start is None or t >= start)]
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
            'path_length': None if length is None else round(length, 6),
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
        'truncated': run.truncated, 'warning': '; '.join(line for line in (run.warning, *notes) if line),
        'messages': run.message_count,
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
        headings = np.array(robot.yaw, dtype=float) if robot.model in plots.HEADING_MODELS else None
        paths.append(plots.RobotPath(robot.name, odom[:, 1:3], length, np.array(waypoints, dtype=float).reshape(-1, 2),
                                     start, robot.goal, headings))
    costs = {robot.name: np.array(robot.cost, dtype=float).reshape(-1, 2) - [run.t0, 0.0]
             for robot in run.robots.values()}
    velocities = []
    for robot in run.robots.values():
        source, series = ('cmd_vel', robot.cmd) if robot.cmd else ('odom', robot.odom_twist)
        velocities.append(plots.Velocities(robot.name, source, robot.model,
                                           np.array(series, dtype=float).reshape(-1, 4) - [run.t0, 0.0, 0.0, 0.0]))
    drawn: dict[str, Any] = {}
    try:   # a figure that cannot be drawn (a hostile recording) must not leave the ones before it open
        drawn['paths.png'] = plots.paths_figure(run.obstacles, run.workspace, paths, text)
        drawn['cost.png'] = plots.cost_figure(costs, text)
        drawn['velocity.png'] = plots.velocity_figure(velocities, text)
    except BaseException:
        plots.close_all(drawn.values())
        raise
    return drawn


def write_figures(run: RecordedRun, out: Path) -> list[Path]:
    """paths.png, cost.png and velocity.png in out; returns their paths."""
    from msg_tools.plots import close_all, save

    drawn = figures(run)
    try:
        return [save(fig, out / name) for name, fig in drawn.items()]
    finally:   # save closes what it wrote; a failed write (a full disk) leaves the rest to close here
        close_all(drawn.values())


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
    files[0].write_text(json.dumps(_json_ready(report), indent=1, allow_nan=False) + '\n')
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
    path = f'{row["path_length"]:.2f} m' if row['path_length'] is not None else 'none (no odometry decoded)'
    return (f'{row["name"]}: {state}{" COLLIDED" if row["collided"] else ""}, path {path}, '
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
