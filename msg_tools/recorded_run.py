"""A recorded run (MCAP) read back: per robot its odometry, commands, plans, waypoints and statuses, and the
run's obstacles, workspace and metadata, as fastep-report measures them.

Anything a recording may hold that a report cannot use (another message type, a coordinate beyond MAX_COORDINATE,
NaN) is left out and counted, and `RecordedRun.warning` says what in one line; a truncated file gives what it
holds. A v2 run's true world comes from its metadata (`read_scenario_data`), held to a scenario file's limits.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

from fastep_core import bounded_yaml
from fastep_core.errors import FastepError
from fastep_core.geometry import Circle, Obstacle
from fastep_core.scenario import Scenario, parse_scenario
from msg_tools.cdr import float64_field, header_stamp, odometry_fields, twist_fields
from msg_tools.interface import (
    CMD_VEL,
    COST,
    GOAL_POSE,
    MAP,
    METADATA_NAME,
    OBSTACLES,
    ODOM,
    PLAN,
    SCENARIO_DATA,
    STAMPED_CMD_VEL_TYPE,
    STATUS,
    TRAILER_POSE,
    TYPES,
    WAYPOINT,
    metadata_key,
    split_robot_topic,
)
from msg_tools.mcap_io import Recording

__all__ = ['MAX_COORDINATE', 'RecordedRun', 'RobotRecord', 'began', 'load_run', 'read_scenario_data']

MAX_COORDINATE = 1e9
"""m: positions, lengths and speeds beyond it (or not finite) are left out of a report (with a warning): a
robot 10^6 km away is a broken message, and sums of squares of such values overflow."""

@dataclass
class RobotRecord:
    """Time series of one robot, times in seconds of log time."""

    name: str
    model: str = 'point_mass'
    odom: list[tuple[float, float, float]] = field(default_factory=list)           # t, x, y
    odom_stamped: list[tuple[float, float, float]] = field(default_factory=list)   # header stamp, x, y
    yaw: list[float] = field(default_factory=list)                                 # of each odom (rad)
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

    def truth(self) -> Scenario | None:
        """A format-v2 run's scenario from the metadata (interface.SCENARIO_DATA): the true world it is judged
        against; None for a v1 run (its /obstacles are the truth) or metadata that is not a scenario."""
        return self.read_truth()[0]

    def read_truth(self) -> tuple[Scenario | None, str]:
        """(truth(), '') or, when the metadata has a scenario_data that is not a scenario, (None, why not)."""
        text = self.metadata.get(SCENARIO_DATA)
        if not text:
            return None, ''
        return read_scenario_data(text)


def _nested_deeper(value: Any, limit: int) -> bool:
    """Are value's lists and dicts nested more than `limit` deep (the outermost at depth 1)? Iterative."""
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, (list, dict)):
            if depth > limit:
                return True
            stack.extend((v, depth + 1) for v in (item.values() if isinstance(item, dict) else item))
    return False


def read_scenario_data(text: str) -> tuple[Scenario | None, str]:
    """(the scenario, '') of a recording's scenario_data (JSON of fastep_core.scenario.scenario_data), or (None,
    one line saying why it is not one). Held to the limits of a scenario file (fastep_core.bounded_yaml): at most
    MAX_BYTES, collections nested at most MAX_DEPTH deep; a bigger one is refused before it is parsed."""
    size = len(text.encode('utf-8', 'replace'))
    if size > bounded_yaml.MAX_BYTES:
        return None, (f'it has {size} bytes, more than a scenario file may have ({bounded_yaml.MAX_BYTES} bytes, '
                      f'{bounded_yaml.MAX_BYTES // 2 ** 20} MiB)')
    deeper = f'collections nested deeper than a scenario file may have them ({bounded_yaml.MAX_DEPTH} levels)'
    try:
        data = json.loads(text)
    except RecursionError:   # json's decoder recurses per level: a few thousand `[` reach Python's limit
        return None, deeper
    except ValueError as exc:   # JSONDecodeError; an integer beyond Python's int conversion limit
        return None, f'not JSON: {" ".join(str(exc).split())[:200]}'
    if _nested_deeper(data, bounded_yaml.MAX_DEPTH):
        return None, deeper
    try:
        return parse_scenario(data, default_name='scenario_data'), ''
    except (ValueError, FastepError) as exc:
        return None, ' '.join(str(exc).split())[:300]


def _robot(robots: dict[str, RobotRecord], name: str) -> RobotRecord:
    if name not in robots:
        robots[name] = RobotRecord(name)
    return robots[name]


# What each topic may carry; anything else (another type, another encoding) is left out with a warning.
_ACCEPTED = {kind: {name} for kind, name in TYPES.items()}
_ACCEPTED[CMD_VEL] = {TYPES[CMD_VEL], STAMPED_CMD_VEL_TYPE}


def _plausible(values: Sequence[float]) -> bool:
    """Finite and within MAX_COORDINATE: a position, length or speed a report can compute and draw with."""
    return all(math.isfinite(v) and abs(v) <= MAX_COORDINATE for v in values)


def _numbers(obstacle: Obstacle) -> tuple[float, ...]:
    if isinstance(obstacle, Circle):
        return (*obstacle.center, obstacle.radius)
    return (*obstacle.start, *obstacle.end)


def _workspace(values: Sequence[float] | None) -> tuple[float, float, float, float] | None:
    """(xmin, ymin, xmax, ymax) if it is a plausible workspace (4 values, min < max), else None."""
    if values is None or len(values) != 4 or not _plausible(values):
        return None
    xmin, ymin, xmax, ymax = (float(v) for v in values)
    return (xmin, ymin, xmax, ymax) if xmin < xmax and ymin < ymax else None


class _Problems:
    """Messages left out while loading, counted per topic and reason, said in one line at the end."""

    def __init__(self) -> None:
        self.counts: dict[tuple[str, str], int] = {}
        self.lines: list[str] = []

    def count(self, topic: str, what: str) -> None:
        self.counts[(topic, what)] = self.counts.get((topic, what), 0) + 1

    def line(self, text: str) -> None:
        self.lines.append(text)

    def summary(self) -> list[str]:
        counted = [f'{n} message(s) on {topic} left out ({what})' for (topic, what), n in self.counts.items()]
        return self.lines + counted


def began(log_time: float, status: Mapping[str, Any], start: float | None) -> float:
    """When a status' message began: its `since` value (a planner's), if it is a time between `start` and the log
    time (not logged before it was sent; on the recording's clock, not another), else the log time."""
    try:
        since = float(status.get('since', ''))
    except (TypeError, ValueError):
        return log_time
    low = -math.inf if start is None else start - 1e-6
    return since if math.isfinite(since) and low <= since <= log_time + 1e-6 else log_time


def load_run(recording: Recording) -> RecordedRun:
    """Collect every robot's series, the obstacles and the workspace from a recording.

    What the report cannot use is left out and said in `warning` (one line): topics of another type or
    encoding than the interface's, messages that do not decode, odometry, points and obstacles that are not
    finite or lie beyond MAX_COORDINATE, a workspace that is not one."""
    from rclpy.serialization import deserialize_message

    from msg_tools import convert
    from msg_tools.ros2_profile import message_class, normalize_type

    problems = _Problems()
    LIMIT = MAX_COORDINATE  # noqa: N806  (a local name: read once per message in the loop below)
    robots: dict[str, RobotRecord] = {}
    kinds: dict[str, tuple[RobotRecord | None, str, str]] = {}   # topic -> robot, kind, pkg/msg/Type
    for topic, info in recording.topics.items():
        parts = split_robot_topic(topic)
        if parts is not None:
            robot: RobotRecord | None = _robot(robots, parts[0])
            kind = parts[1]
        elif topic in (OBSTACLES, MAP):
            robot, kind = None, topic
        else:
            continue
        try:
            type_name = normalize_type(info.type)
        except FastepError:
            type_name = info.type
        if info.message_encoding != 'cdr' or type_name not in _ACCEPTED[kind]:
            problems.line(f'{topic} left out: it holds {info.type or "schemaless"} ({info.message_encoding}), '
                          f'not {" or ".join(sorted(_ACCEPTED[kind]))} (cdr)')
            continue
        if kind == TRAILER_POSE:
            assert robot is not None
            robot.model = 'tractor_trailer'
        else:
            kinds[topic] = (robot, kind, type_name)
    classes: dict[str, type] = {}

    def decode(type_name: str, data: bytes) -> Any:
        if type_name not in classes:
            classes[type_name] = message_class(type_name)
        return deserialize_message(data, classes[type_name])

    def point(pose: Any) -> tuple[float, float]:
        p = convert.pose_stamped_to_point(pose)
        if not _plausible(p):
            raise ValueError(f'a point that is not finite or beyond {MAX_COORDINATE:g} m')
        return p

    obstacles: tuple[float, list[Obstacle]] | None = None
    workspace: tuple[float, tuple[float, float, float, float]] | None = None
    waypoints: dict[str, list[tuple[float, tuple[float, float]]]] = {name: [] for name in robots}
    plans: dict[str, tuple[float, list[tuple[float, float]]]] = {}
    goals: dict[str, list[tuple[float, tuple[float, float]]]] = {name: [] for name in robots}
    algorithm = ''
    # File order (fast); every series is sorted by time below.
    cmd_vel_type = TYPES[CMD_VEL]
    for topic, _, log_time, _, data, _, _ in recording.raw_messages(list(kinds), log_time_order=False):
        t = log_time * 1e-9
        robot, kind, type_name = kinds[topic]
        try:
            if kind == ODOM:   # the most frequent first
                assert robot is not None
                v = odometry_fields(data)
                if v is None:
                    m = decode(type_name, data)
                    p, q, tw = m.pose.pose.position, m.pose.pose.orientation, m.twist.twist
                    v = (p.x, p.y, q.x, q.y, q.z, q.w, tw.linear.x, tw.linear.y, tw.angular.z)
                    sec, nanosec = m.header.stamp.sec, m.header.stamp.nanosec
                else:
                    sec, nanosec = header_stamp(data)
                # Chained comparisons: False for NaN and inf too, and 30 times faster than math.isfinite + abs.
                if not (-LIMIT <= v[0] <= LIMIT and -LIMIT <= v[1] <= LIMIT and -LIMIT <= v[6] <= LIMIT
                        and -LIMIT <= v[7] <= LIMIT and -LIMIT <= v[8] <= LIMIT):
                    problems.count(topic, f'not finite or beyond {LIMIT:g}')
                    continue
                robot.odom.append((t, v[0], v[1]))
                robot.odom_stamped.append((sec + nanosec * 1e-9, v[0], v[1]))
                robot.yaw.append(math.atan2(2.0 * (v[5] * v[4] + v[2] * v[3]), 1.0 - 2.0 * (v[3] * v[3] + v[4] * v[4])))
                robot.odom_twist.append((t, v[6], v[7], v[8]))
                continue
            if kind == OBSTACLES:
                found = convert.marker_array_to_obstacles(decode(type_name, data))
                if not all(_plausible(_numbers(o)) for o in found):
                    raise ValueError(f'an obstacle beyond {MAX_COORDINATE:g} m')
                if obstacles is None or t >= obstacles[0]:
                    obstacles = (t, found)
                continue
            if kind == MAP:
                space = _workspace(convert.occupancy_grid_workspace(decode(type_name, data)))
                if space is None:
                    raise ValueError('its extent is not a plausible workspace')
                if workspace is None or t >= workspace[0]:
                    workspace = (t, space)
                continue
            assert robot is not None
            if kind == CMD_VEL:
                c = twist_fields(data) if type_name == cmd_vel_type else None
                if c is None:
                    m = decode(type_name, data)
                    tw = m.twist if hasattr(m, 'twist') else m  # TwistStamped or Twist
                    c = (tw.linear.x, tw.linear.y, tw.angular.z)
                if not (-LIMIT <= c[0] <= LIMIT and -LIMIT <= c[1] <= LIMIT and -LIMIT <= c[2] <= LIMIT):
                    problems.count(topic, f'not finite or beyond {LIMIT:g}')
                    continue
                robot.cmd.append((t, *c))
            elif kind == COST:
                f = float64_field(data)
                robot.cost.append((t, float(decode(type_name, data).data) if f is None else f))
            elif kind == WAYPOINT:
                waypoints[robot.name].append((t, point(decode(type_name, data))))
            elif kind == PLAN:
                path = [point(pose) for pose in decode(type_name, data).poses]
                if robot.name not in plans or t >= plans[robot.name][0]:
                    plans[robot.name] = (t, path)
            elif kind == STATUS:
                robot.statuses.append((t, convert.diagnostic_to_dict(decode(type_name, data))))
            elif kind == GOAL_POSE:
                goals[robot.name].append((t, point(decode(type_name, data))))
        except Exception as exc:  # rclpy's decoder raises several kinds; every one means the same here
            problems.count(topic, ' '.join(f'{type(exc).__name__}: {exc}'.split())[:200])
    for robot in robots.values():
        for series in (robot.odom, robot.odom_stamped, robot.odom_twist, robot.cmd, robot.cost, robot.statuses):
            series.sort(key=lambda row: row[0])  # stable: equal times keep file order
        for _, point_ in sorted(waypoints[robot.name], key=lambda row: row[0]):
            if point_ not in robot.waypoints:
                robot.waypoints.append(point_)
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
            space = _workspace([float(v) for v in meta['workspace'].split(',')])
        except ValueError:
            space = None
        if space is None:
            problems.line(f'the metadata\'s workspace {meta["workspace"][:80]!r} is not xmin,ymin,xmax,ymax with '
                          f'min < max, finite, within {MAX_COORDINATE:g}: left out')
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
    warning = '; '.join(line for line in (recording.warning(), *problems.summary()) if line)
    return RecordedRun(recording.path, ordered, [] if obstacles is None else obstacles[1], space, meta,
                       meta.get('algorithm', algorithm), meta.get('scenario', ''), t0, recording.truncated,
                       warning, recording.message_count)
