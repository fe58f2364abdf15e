"""Scenario files (formats v1 and v2, YAML): a workspace, its obstacles, the robots and optional planner overrides.

Format v2 adds moving circles, obstacles missing from the map, misplaced ones, a robot's laser, the
`diff_drive` model and its `dynamics` (a base with mass: fastep_core/dynamics) and `footprint` (its real outline:
fastep_core/footprint.py); every v1 file loads and means
what it did. `Scenario.world` is the true world of the still obstacles; `Scenario.obstacle_specs` lists every
obstacle with its v2 keys, and fastep_core/dynamic_world.py turns them into the truth over time and the
planner's map.

A scenario is loaded from a path or a built-in name (``fastep_core/scenarios/*.yaml``), parsed with PyYAML's
safe loader within bounds (:mod:`fastep_core.bounded_yaml`), and validated strictly (values read through
:mod:`fastep_core.yaml_checks`): unknown keys are an error at every level, coordinates must be finite numbers,
starts and goals must be free. Every problem raises :class:`~fastep_core.errors.ScenarioError` with a one-line
message naming the file and the key path, e.g. ``scenario 'x.yaml': robots[1].radius must be > 0, got -1``.

The format is documented in ``docs/scenarios.md``.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import yaml

from fastep_core import bounded_yaml
from fastep_core import yaml_checks as check
from fastep_core.dynamic_world import Motion, ObstacleSpec
from fastep_core.dynamics.params import BaseDynamics, dynamics_data, robot_dynamics
from fastep_core.errors import GoalError, ParameterError, ScenarioError
from fastep_core.footprint import Footprint
from fastep_core.geometry import Circle, Obstacle, Segment, point_segment_distance
from fastep_core.kinematics.tractor_trailer import wrap_angle
from fastep_core.planning.params import PlannerParams
from fastep_core.sensing.laser import FULL_TURN_TOLERANCE, MAX_BEAMS, LaserSpec, beam_angles, way_problem
from fastep_core.world import World

__all__ = [
    'MODELS', 'SCENARIO_MODELS', 'ObstacleSpec', 'Motion', 'RobotSpec', 'Scenario',
    'load_scenario', 'parse_scenario', 'scenario_data', 'builtin_names', 'builtin_path',
]

MODELS: tuple[str, ...] = ('point_mass', 'tractor_trailer', 'diff_drive')
"""Robot models the planners and the in-process simulator implement."""
SCENARIO_MODELS: tuple[str, ...] = MODELS
"""Robot models a scenario may name (format v2 adds diff_drive)."""

_START_LENGTH = {'point_mass': 2, 'tractor_trailer': 4, 'diff_drive': 3}
_START_FORM = {2: '[x, y]', 3: '[x, y, theta]', 4: '[x, y, theta0, theta1]'}
_TOP_KEYS = ('name', 'description', 'workspace', 'obstacles', 'robots', 'planner')
_ROBOT_KEYS = ('name', 'model', 'start', 'goal', 'radius')
_OPTIONAL_ROBOT_KEYS = ('sensor', 'dynamics', 'footprint')
_SENSOR_KEYS = ('range', 'fov', 'beams', 'noise', 'mount')
_OBSTACLE_EXTRAS = ('motion', 'known', 'position_sigma')   # v2: beside the shape key of an obstacle entry
_MOTION_KEYS = ('waypoints', 'speed')
_TRACTOR_KEYS = ('length', 'trailer_length', 'width', 'hitch_offset')
_ROBOT_NAME = re.compile(r'[A-Za-z_][A-Za-z0-9_]*')
_IGNORED_PREFIX = 'x_'
_SUFFIX = '.yaml'
# Relative slack when comparing a tractor-trailer's radius with its clearance sqrt(L^2 + b^2) / 2.
_CLEARANCE_RTOL = 1e-9
# Start headings beyond one turn either way are normalised into (-pi, pi]; within it they are kept as written.
_HEADING_TURN = math.tau


@dataclass(frozen=True)
class RobotSpec:
    """One robot of a scenario: its model, start pose, goal and body dimensions (metres, radians)."""

    name: str
    model: str                    # 'point_mass' | 'tractor_trailer' | 'diff_drive'
    start: tuple[float, ...]      # (x, y) point_mass; (x, y, theta0, theta1) tractor_trailer; (x, y, theta) diff_drive
    goal: tuple[float, float]
    radius: float                 # safety radius (m)
    length: float = 1.0           # tractor_trailer only: L, tractor mid-axle length (m)
    trailer_length: float = 1.0   # tractor_trailer only: Lt (m)
    width: float = 0.5            # tractor_trailer only: b, tractor width (m)
    hitch_offset: float = 0.0     # tractor_trailer only: c in eq. 13 (m)
    sensor: LaserSpec | None = None   # v2: a planar laser scanner at the reference point
    goal_heading: float | None = None  # v2, diff_drive: the heading to end in (radians; goal [x, y, theta])
    dynamics: BaseDynamics | None = None   # v2, diff_drive: a base with mass (a physics plant); None: kinematic
    footprint: Footprint | None = None   # v2, diff_drive: the real outline in the robot frame; radius covers it


@dataclass(frozen=True)
class Scenario:
    """A validated scenario: the world, its robots and the planner parameters to use."""

    name: str
    world: World
    robots: tuple[RobotSpec, ...]
    planner: PlannerParams
    description: str = ''
    obstacles: tuple[ObstacleSpec, ...] | None = None   # every obstacle with its v2 keys; None: world's, as v1

    @property
    def obstacle_specs(self) -> tuple[ObstacleSpec, ...]:
        """Every obstacle in file order with its v2 keys (a scenario built from a World alone: all still)."""
        if self.obstacles is None:
            return tuple(ObstacleSpec(o) for o in self.world.obstacle_list)
        return self.obstacles

    @property
    def is_static(self) -> bool:
        """Does it mean what a v1 file could say (no mover, no unknown or misplaced obstacle)?"""
        return all(o.v1 for o in self.obstacle_specs)


def _fail(label: str, message: str) -> ScenarioError:
    return ScenarioError(check.one_line(f'scenario {label!r}: {message}'))


def _goal(value: Any, path: str, model: str) -> tuple[tuple[float, float], float | None]:
    """A goal [x, y], or for a robot that turns in place (diff_drive) also [x, y, theta]: where to end, facing."""
    if model == 'diff_drive' and isinstance(value, list) and len(value) == 3:
        x, y, theta = check.numbers(value, path, 3, '[x, y, theta]')
        return (x, y), _heading(theta)
    return check.point(value, path), None


# ----------------------------------------------------------------------------------------------- sections

def _workspace(value: Any) -> tuple[float, float, float, float]:
    xmin, ymin, xmax, ymax = check.numbers(value, 'workspace', 4, '[xmin, ymin, xmax, ymax]')
    if not xmin < xmax:
        raise check.Invalid(f'workspace needs xmin < xmax, got xmin={xmin:g}, xmax={xmax:g}')
    if not ymin < ymax:
        raise check.Invalid(f'workspace needs ymin < ymax, got ymin={ymin:g}, ymax={ymax:g}')
    return xmin, ymin, xmax, ymax


def _circle(value: Any, path: str) -> Circle:
    body = check.mapping(value, path)
    check.keys(body, path, ('center', 'radius'), ('center', 'radius'))
    return Circle(check.point(body['center'], f'{path}.center'), check.positive(body['radius'], f'{path}.radius'))


def _segment(value: Any, path: str) -> Segment:
    body = check.mapping(value, path)
    check.keys(body, path, ('start', 'end'), ('start', 'end'))
    start, end = check.point(body['start'], f'{path}.start'), check.point(body['end'], f'{path}.end')
    if start == end:
        raise check.Invalid(f'{path}: start and end must differ, both are [{start[0]:g}, {start[1]:g}]')
    return Segment(start, end)


_OBSTACLE_PARSERS: dict[str, Callable[[Any, str], Obstacle]] = {'circle': _circle, 'segment': _segment}


def _obstacle(value: Any, path: str) -> ObstacleSpec:
    entry = check.mapping(value, path)
    kinds = ', '.join(_OBSTACLE_PARSERS)
    for key in entry:
        if key not in _OBSTACLE_PARSERS and key not in _OBSTACLE_EXTRAS:
            raise check.Invalid(f'{path}: unknown key {check.show(key)} '
                                f'(allowed: {kinds}, {", ".join(_OBSTACLE_EXTRAS)})')
    shapes = [key for key in entry if key in _OBSTACLE_PARSERS]
    if len(shapes) != 1:
        raise check.Invalid(f'{path} must have exactly one key ({kinds}) besides {", ".join(_OBSTACLE_EXTRAS)}, '
                            f'got {check.show(sorted(entry))}')
    kind = shapes[0]
    shape = _OBSTACLE_PARSERS[kind](entry[kind], f'{path}.{kind}')
    motion = None
    if 'motion' in entry:
        if not isinstance(shape, Circle):
            raise check.Invalid(f'{path}.motion: only circles move, this obstacle is a {kind}')
        motion = _motion(entry['motion'], f'{path}.motion')
    known = check.boolean(entry['known'], f'{path}.known') if 'known' in entry else True
    sigma = check.non_negative(entry['position_sigma'], f'{path}.position_sigma') if 'position_sigma' in entry else 0.0
    spec = ObstacleSpec(shape, motion, known, sigma)
    _check_motion_length(spec, path)
    return spec


def _motion(value: Any, path: str) -> Motion:
    body = check.mapping(value, path)
    check.keys(body, path, _MOTION_KEYS, _MOTION_KEYS)
    points = body['waypoints']
    if not isinstance(points, list) or not points:
        raise check.Invalid(f'{path}.waypoints must be a non-empty list of [x, y] points, got {check.show(points)}')
    waypoints = tuple(check.point(p, f'{path}.waypoints[{i}]') for i, p in enumerate(points))
    return Motion(waypoints, check.positive(body['speed'], f'{path}.speed'))


def _check_sigmas(obstacles: Sequence[ObstacleSpec], workspace: tuple[float, float, float, float]) -> None:
    """A map error is at most the workspace's larger side: beyond it the obstacle is not misplaced but elsewhere
    (1e300 loaded, and the planner's geometry overflowed: `no valid path` on an open field)."""
    side = max(workspace[2] - workspace[0], workspace[3] - workspace[1])
    for i, spec in enumerate(obstacles):
        if spec.position_sigma > side:
            raise check.Invalid(f'obstacles[{i}].position_sigma must be at most the workspace\'s larger side '
                                f'({side:g} m), got {spec.position_sigma:g}')


def _check_motion_length(spec: ObstacleSpec, path: str) -> None:
    """The polyline's length must be a finite number (points near +-1e308 apart overflow it)."""
    if spec.motion is None or not isinstance(spec.shape, Circle):
        return
    vertices = np.array([spec.shape.center, *spec.motion.waypoints], dtype=float)
    with np.errstate(over='ignore', invalid='ignore'):
        length = float(np.sqrt((np.diff(vertices, axis=0) ** 2).sum(axis=1)).sum())
    if not math.isfinite(length):
        raise check.Invalid(f'{path}.motion.waypoints: the path is too long to measure (its length overflows)')


def _obstacles(value: Any) -> tuple[ObstacleSpec, ...]:
    if value is None:
        return ()
    return tuple(_obstacle(v, f'obstacles[{i}]') for i, v in enumerate(check.as_list(value, 'obstacles')))


def _sensor(value: Any, path: str) -> LaserSpec:
    """A robot's laser scanner: every key optional (defaults: fastep_core/sensing/laser.py's LaserSpec)."""
    body = check.mapping(value if value is not None else {}, path)
    check.keys(body, path, _SENSOR_KEYS, ())
    defaults = LaserSpec()
    rng = check.positive(body['range'], f'{path}.range') if 'range' in body else defaults.range
    fov = defaults.fov
    if 'fov' in body:
        fov = check.number(body['fov'], f'{path}.fov')
        if not 0.0 < fov <= 2.0 * math.pi + FULL_TURN_TOLERANCE:
            raise check.Invalid(f'{path}.fov must be in (0, 2 pi] radians (6.2832 is a full turn), '
                                f'got {check.show(body["fov"])}')
        fov = min(fov, 2.0 * math.pi)
    beams = check.integer(body['beams'], f'{path}.beams', 1, MAX_BEAMS) if 'beams' in body else defaults.beams
    noise = check.non_negative(body['noise'], f'{path}.noise') if 'noise' in body else defaults.noise
    mount = check.numbers(body['mount'], f'{path}.mount', 3, '[x, y, yaw]') if 'mount' in body else defaults.mount
    return LaserSpec(rng, fov, beams, noise, (mount[0], mount[1], mount[2]))


def _robot_name(value: Any, path: str) -> str:
    if not isinstance(value, str) or not _ROBOT_NAME.fullmatch(value):
        raise check.Invalid(f'{path} must match [A-Za-z_][A-Za-z0-9_]* (it becomes a ROS namespace), '
                            f'got {check.show(value)}')
    return value


def _model(value: Any, path: str) -> str:
    if not isinstance(value, str) or value not in SCENARIO_MODELS:
        raise check.Invalid(f'{path} must be one of {", ".join(SCENARIO_MODELS)}, got {check.show(value)}')
    return str(value)


def _tractor_dimensions(data: Mapping[str, Any], path: str) -> dict[str, float]:
    dims = {}
    for key in ('length', 'trailer_length', 'width'):
        if key in data:
            dims[key] = check.positive(data[key], check.key_path(path, key))
    if 'hitch_offset' in data:
        dims['hitch_offset'] = check.non_negative(data['hitch_offset'], check.key_path(path, 'hitch_offset'))
    return dims


def _footprint(value: Any, path: str, model: str) -> Footprint:
    """A robot's outline: [[x, y], ...] in its frame, counter-clockwise (clockwise is reordered), base_link inside.
    Only a diff_drive robot has one: a point mass has no heading to turn it by, and a tractor-trailer's body is
    its length and width."""
    if model != 'diff_drive':
        raise check.Invalid(f'{path} is only valid for model diff_drive (a robot with a heading), not {model}')
    if not isinstance(value, list):
        raise check.Invalid(f'{path} must be a list of [x, y] vertices, got {check.show(value)}')
    vertices = [check.point(p, f'{path}[{i}]') for i, p in enumerate(value)]
    try:
        return Footprint.parse(vertices, what=path)
    except ValueError as exc:
        raise check.Invalid(str(exc)) from None


def _radius(data: Mapping[str, Any], path: str, footprint: Footprint | None) -> float:
    """The safety radius: as given, or with a footprint and no radius the footprint's circumscribed one (what the
    planners keep clear wherever they need a circle); a given radius must cover the footprint."""
    if 'radius' not in data:
        if footprint is None:
            raise check.Invalid(f'{path}: missing required key \'radius\' (or a footprint)')
        return footprint.radius
    radius = check.positive(data['radius'], f'{path}.radius')
    if footprint is not None and not footprint.holds(radius):
        raise check.Invalid(f'{path}.radius {radius:g} m is below the footprint\'s circumscribed radius '
                            f'{footprint.radius:.6g} m (its farthest vertex from base_link)')
    return radius


def _robot(value: Any, path: str) -> RobotSpec:
    data = check.mapping(value, path)
    required = tuple(key for key in _ROBOT_KEYS if key != 'radius' or 'footprint' not in data)
    check.keys(data, path, _ROBOT_KEYS + _TRACTOR_KEYS + _OPTIONAL_ROBOT_KEYS, required)
    name = _robot_name(data['name'], f'{path}.name')
    model = _model(data['model'], f'{path}.model')
    if model != 'tractor_trailer':
        for key in _TRACTOR_KEYS:
            if key in data:
                raise check.Invalid(f'{path}.{key} is only valid for model tractor_trailer, not {model}')
    n = _START_LENGTH[model]
    start = check.numbers(data['start'], f'{path}.start', n, _START_FORM[n])
    start = start[:2] + tuple(_heading(theta) for theta in start[2:])
    goal, heading = _goal(data['goal'], f'{path}.goal', model)
    footprint = _footprint(data['footprint'], f'{path}.footprint', model) if 'footprint' in data else None
    robot = RobotSpec(name=name, model=model, start=start, goal=goal, goal_heading=heading,
                      radius=_radius(data, path, footprint), footprint=footprint,
                      sensor=_sensor(data['sensor'], f'{path}.sensor') if 'sensor' in data else None,
                      dynamics=robot_dynamics(data['dynamics'], f'{path}.dynamics', model)
                      if 'dynamics' in data else None,
                      **_tractor_dimensions(data, path))
    if model == 'tractor_trailer':
        _check_tractor_radius(robot, path)
    if robot.sensor is not None and math.hypot(*robot.sensor.mount[:2]) > robot.radius:
        raise check.Invalid(f'{path}.sensor.mount must lie on the robot: within its radius {robot.radius:g} m of its '
                            f'reference point, got {list(robot.sensor.mount)}')
    if robot.sensor is not None:
        spec = robot.sensor
        angle_min, increment, angles = beam_angles(spec)
        problem = way_problem(angle_min, float(angles[-1]), increment, spec.beams, spec.range, spec.mount[2],
                              robot.radius)
        if problem:
            raise check.Invalid(f'{path}.sensor cannot see the robot\'s way: {problem}')
    return robot


def _heading(theta: float) -> float:
    """A start heading as given, or normalised into (-pi, pi] when it is more than a turn either way.

    A heading of 1e15 rad is a direction like any other, but as a float it has 0.125 rad steps: the model's
    heading changes of a few mrad per step were lost in it, the robot could not turn and drove off the map.
    Normalising keeps the direction (atan2 of sin and cos: libm reduces exactly, unlike a remainder by the
    float 2 pi); headings within a turn stay bit for bit what the file says.
    """
    return theta if abs(theta) <= _HEADING_TURN else wrap_angle(theta)


def _check_tractor_radius(robot: RobotSpec, path: str) -> None:
    """The paper's clearance (section VII-C): the safety radius must cover the tractor, sqrt(L^2 + b^2) / 2."""
    needed = math.hypot(robot.length, robot.width) / 2.0
    if robot.radius < needed * (1.0 - _CLEARANCE_RTOL):
        raise check.Invalid(f'{path}.radius must be >= sqrt(length^2 + width^2)/2 = {needed:.4g} for a '
                            f'tractor_trailer, got {robot.radius:g}')


def _robots(value: Any) -> tuple[RobotSpec, ...]:
    items = check.as_list(value, 'robots')
    if not items:
        raise check.Invalid('robots must list at least one robot, got []')
    robots = tuple(_robot(v, f'robots[{i}]') for i, v in enumerate(items))
    seen: dict[str, int] = {}
    for i, robot in enumerate(robots):
        if robot.name in seen:
            raise check.Invalid(f'robots[{i}].name {check.show(robot.name)} is already used by '
                                f'robots[{seen[robot.name]}]')
        seen[robot.name] = i
    return robots


def _planner(value: Any) -> PlannerParams:
    """The overrides, each checked to be a finite number here first: PlannerParams' messages show the whole
    value (and math.isfinite raises OverflowError on a 400-digit integer)."""
    defaults = PlannerParams()
    if value is None:
        return defaults
    overrides = check.mapping(value, 'planner')
    names = PlannerParams.names()
    unknown = sorted(key for key in overrides if key not in names)
    if unknown:
        listed = ', '.join(check.show(key, 40).strip("'") for key in unknown[:10])
        more = f', ... ({len(unknown)} in all)' if len(unknown) > 10 else ''
        raise check.Invalid(f'planner: unknown planner parameter(s): {listed}{more}')
    for key, item in overrides.items():
        if check.text_number_hint(item):
            check.number(item, f'planner.{key}')   # raises, with the hint
        if check.finite(item) is None:
            raise check.Invalid(f'planner.{key}: planner parameter {key} must be a finite number, '
                                f'got {check.show(item)}')
        _apply(defaults, {key: item}, f'planner.{key}')
    return _apply(defaults, overrides, 'planner')


def _apply(params: PlannerParams, overrides: Mapping[str, Any], path: str) -> PlannerParams:
    try:
        return params.with_overrides(overrides)
    except ParameterError as exc:
        raise check.Invalid(f'{path}: {exc}') from None


def _description(value: Any) -> str:
    if not isinstance(value, str):
        raise check.Invalid(f'description must be a string, got {check.show(value)}')
    return str(value)


# ----------------------------------------------------------------------------------------------- placement

def _check_placement(world: World, robots: Sequence[RobotSpec]) -> None:
    """Starts and goals lie inside the workspace, clear of obstacles by each robot's radius; a robot with a
    footprint by its outline instead, at the start's heading and at the goal's (its circle where the goal has
    none: it may arrive facing any way)."""
    for i, robot in enumerate(robots):
        footprint = robot.footprint
        for what, point, heading in (('start', robot.start[:2], robot.start[2] if len(robot.start) > 2 else None),
                                     ('goal', robot.goal, robot.goal_heading)):
            try:
                world.check_point(point, 0.0 if footprint is not None and heading is not None else robot.radius,
                                  what=what)
            except GoalError as exc:
                raise check.Invalid(f'robots[{i}] ({robot.name}): {exc}') from None
            if footprint is not None and heading is not None:
                clearance = float(footprint.clearance([point[0], point[1], heading], world.obstacles))
                if clearance < 0.0:
                    raise check.Invalid(f'robots[{i}] ({robot.name}): {what} ({point[0]:g}, {point[1]:g}) is '
                                        f'occupied: its footprint at heading {heading:g} overlaps an obstacle by '
                                        f'{-clearance:.3g} m')


def _check_pairs(robots: Sequence[RobotSpec]) -> None:
    """No two robots start (or end) closer than the sum of their radii."""
    for i, first in enumerate(robots):
        for j in range(i + 1, len(robots)):
            second = robots[j]
            reach = first.radius + second.radius
            for what, p, q in (('starts', first.start, second.start), ('goals', first.goal, second.goal)):
                gap = math.hypot(p[0] - q[0], p[1] - q[1])
                if gap < reach:
                    raise check.Invalid(f'robots[{i}] ({first.name}) and robots[{j}] ({second.name}): {what} are '
                                        f'{gap:.3g} m apart, closer than the sum of their radii {reach:g} m')


def _check_movers(obstacles: Sequence[ObstacleSpec], robots: Sequence[RobotSpec]) -> None:
    """A mover may not start on a robot's start (they would touch at t = 0), nor pass over a robot's goal
    (a robot that has arrived waits there: the mover would run it down, whatever its planner did). Its path
    may cross a start: the robot can leave it in time (docs/scenarios.md, "Format v2")."""
    for k, spec in enumerate(obstacles):
        if spec.motion is None or not isinstance(spec.shape, Circle):
            continue
        path = np.array([spec.shape.center, *spec.motion.waypoints], dtype=float)
        a, b = path[:-1], path[1:]   # at least one segment: waypoints is never empty
        for i, robot in enumerate(robots):
            reach = spec.shape.radius + robot.radius
            gap = math.hypot(spec.shape.center[0] - robot.start[0], spec.shape.center[1] - robot.start[1])
            if gap < reach:
                raise check.Invalid(f'obstacles[{k}] (a mover) starts {gap:.3g} m from robots[{i}] ({robot.name})\'s '
                                    f'start, closer than the sum of their radii {reach:g} m')
            goal = np.array(robot.goal, dtype=float)
            near = float(point_segment_distance(goal, a, b).min())
            if near < reach:
                raise check.Invalid(f'obstacles[{k}].motion: the mover passes {near:.3g} m from robots[{i}] '
                                    f'({robot.name})\'s goal, closer than the sum of their radii {reach:g} m (an '
                                    f'arrived robot waits there)')


# ----------------------------------------------------------------------------------------------- parsing

def _scenario_name(data: Mapping[str, Any], default_name: str) -> str:
    return check.text(data['name'], 'name') if 'name' in data else default_name


def _build(data: Any, default_name: str) -> Scenario:
    if not isinstance(data, dict):
        what = 'an empty document' if data is None else f'{type(data).__name__} {check.show(data)}'
        raise check.Invalid(f'the top level must be a mapping, got {what}')
    top = check.mapping(data, 'top level')
    for key in top:
        if key not in _TOP_KEYS and not key.startswith(_IGNORED_PREFIX):
            raise check.Invalid(f'unknown top-level key {check.show(key)} (allowed: {", ".join(_TOP_KEYS)}, '
                                f'and keys starting with {_IGNORED_PREFIX!r}, which are ignored)')
    for key in ('workspace', 'robots'):
        if key not in top:
            raise check.Invalid(f'missing required top-level key {key!r}')
    name = _scenario_name(top, default_name)
    description = _description(top.get('description', ''))
    obstacles = _obstacles(top.get('obstacles'))
    # The true world of the still obstacles (known or not, where they really are): what starts, goals and
    # collisions are judged against; movers are judged over time (fastep_core/dynamic_world.py).
    workspace = _workspace(top['workspace'])
    _check_sigmas(obstacles, workspace)
    world = World.from_obstacles(workspace, [o.shape for o in obstacles if o.still])
    robots = _robots(top['robots'])
    planner = _planner(top.get('planner'))
    _check_placement(world, robots)
    _check_pairs(robots)
    _check_movers(obstacles, robots)
    return Scenario(name=name, world=world, robots=robots, planner=planner, description=description,
                    obstacles=obstacles)


def _parse(data: Any, default_name: str, label: str) -> Scenario:
    try:
        return _build(data, default_name)
    except check.Invalid as exc:
        raise _fail(label, str(exc)) from None


def parse_scenario(data: object, *, default_name: str = 'scenario') -> Scenario:
    """Validate an already-loaded mapping and build a Scenario.

    Load untrusted text with ``bounded_yaml.load`` (what ``load_scenario`` does), not ``yaml.safe_load``: the
    validation walks the lists it is given, and an alias bomb's are 10^9 items long.

    ``default_name`` is the scenario's name when the mapping has no ``name:`` key; error messages name the
    scenario by its ``name:`` if that is a usable string, else by ``default_name``.
    """
    label = default_name
    if isinstance(data, dict) and isinstance(data.get('name'), str) and data['name'].strip():
        label = data['name']
    return _parse(data, default_name, label)


def scenario_data(scenario: Scenario) -> dict[str, Any]:
    """The mapping parse_scenario makes `scenario` from (format v1 where v1 says it all, v2 keys where needed):
    a run's scenario written into its recording, read back there (parse_scenario(scenario_data(s)) == s)."""
    obstacles: list[dict[str, Any]] = []
    for spec in scenario.obstacle_specs:
        shape = spec.shape
        entry: dict[str, Any] = ({'circle': {'center': list(shape.center), 'radius': shape.radius}}
                                 if isinstance(shape, Circle) else
                                 {'segment': {'start': list(shape.start), 'end': list(shape.end)}})
        if spec.motion is not None:
            entry['motion'] = {'waypoints': [list(p) for p in spec.motion.waypoints], 'speed': spec.motion.speed}
        if not spec.known:
            entry['known'] = False
        if spec.position_sigma > 0.0:
            entry['position_sigma'] = spec.position_sigma
        obstacles.append(entry)
    robots: list[dict[str, Any]] = []
    for robot in scenario.robots:
        item: dict[str, Any] = {'name': robot.name, 'model': robot.model, 'start': list(robot.start),
                                'goal': list(robot.goal) + ([] if robot.goal_heading is None else [robot.goal_heading]),
                                'radius': robot.radius}
        if robot.model == 'tractor_trailer':
            item.update(length=robot.length, trailer_length=robot.trailer_length, width=robot.width,
                        hitch_offset=robot.hitch_offset)
        if robot.sensor is not None:
            item['sensor'] = {'range': robot.sensor.range, 'fov': robot.sensor.fov, 'beams': robot.sensor.beams,
                              'noise': robot.sensor.noise,
                              **({'mount': list(robot.sensor.mount)} if any(robot.sensor.mount) else {})}
        if robot.dynamics is not None:
            item['dynamics'] = dynamics_data(robot.dynamics)
        if robot.footprint is not None:
            item['footprint'] = robot.footprint.to_list()
        robots.append(item)
    defaults = PlannerParams()
    planner = {name: getattr(scenario.planner, name) for name in PlannerParams.names()
               if getattr(scenario.planner, name) != getattr(defaults, name)}
    data: dict[str, Any] = {'name': scenario.name, 'workspace': list(scenario.world.workspace),
                            'obstacles': obstacles, 'robots': robots}
    if scenario.description:
        data['description'] = scenario.description
    if planner:
        data['planner'] = planner
    return data


# ----------------------------------------------------------------------------------------------- files

def _yaml_error(exc: yaml.YAMLError) -> str:
    """One line for a YAML error, with the (1-based) line and column where PyYAML knows them."""
    what = 'YAML beyond the limits of scenario files' if isinstance(exc, bounded_yaml.LimitError) else \
        'invalid YAML'
    if isinstance(exc, yaml.MarkedYAMLError):
        mark = exc.problem_mark or exc.context_mark
        parts = [p for p in (exc.context, exc.problem) if p]
        where = f' at line {mark.line + 1}, column {mark.column + 1}' if mark is not None else ''
        return f'{what}{where}: {"; ".join(parts) or type(exc).__name__}'
    return f'{what}: {check.one_line(str(exc))[:200]}'


def _too_big(size: int) -> str:
    return f'the file has {size} bytes, more than scenario files may have ({bounded_yaml.MAX_BYTES}, ' \
           f'{bounded_yaml.MAX_BYTES // 2 ** 20} MiB)'


def _load_bytes(raw: bytes, default_name: str, label: str) -> Scenario:
    if len(raw) > bounded_yaml.MAX_BYTES:
        raise _fail(label, _too_big(len(raw)))
    try:
        data = bounded_yaml.load(raw)
    except yaml.YAMLError as exc:
        raise _fail(label, _yaml_error(exc)) from None
    return _parse(data, default_name, label)


def _builtin_dir() -> Traversable:
    return resources.files('fastep_core') / 'scenarios'


def _builtin_resource(name: str) -> Traversable | None:
    if name not in builtin_names():
        return None
    return _builtin_dir() / f'{name}{_SUFFIX}'


def builtin_names() -> list[str]:
    """Sorted names of the built-in scenarios (``fastep_core/scenarios/*.yaml``)."""
    folder = _builtin_dir()
    if not folder.is_dir():
        return []
    return sorted(entry.name[:-len(_SUFFIX)] for entry in folder.iterdir()
                  if entry.name.endswith(_SUFFIX) and entry.is_file())


def _unknown_builtin(name: str) -> ScenarioError:
    names = builtin_names()
    listed = ', '.join(names) if names else '(none installed)'
    return _fail(name, f'no such file and no built-in scenario of that name (built-ins: {listed})')


def builtin_path(name: str) -> Path:
    """The file of built-in scenario ``name``; ScenarioError (listing the built-ins) if there is none."""
    resource = _builtin_resource(name)
    if resource is None:
        raise _unknown_builtin(name)
    return Path(str(resource))


def _looks_like_path(text: str) -> bool:
    return os.sep in text or (os.altsep is not None and os.altsep in text) or text.endswith(('.yaml', '.yml'))


def load_scenario(source: str | os.PathLike[str]) -> Scenario:
    """Load and validate a scenario from a YAML file path or a built-in name (a file path wins)."""
    label = os.fspath(source)
    path = Path(label)
    if path.is_file():
        try:
            size = path.stat().st_size
            if size > bounded_yaml.MAX_BYTES:   # before reading it: a scenario path may name any file
                raise _fail(label, _too_big(size))
            raw = path.read_bytes()
        except OSError as exc:
            raise _fail(label, f'cannot read the file: {exc.strerror or exc}') from None
        return _load_bytes(raw, path.stem, label)
    resource = _builtin_resource(label) if isinstance(source, str) else None
    if resource is not None:
        return _load_bytes(resource.read_bytes(), label, label)
    if path.exists():
        raise _fail(label, 'is not a regular file')
    if _looks_like_path(label) or not isinstance(source, str):
        raise _fail(label, 'file not found')
    raise _unknown_builtin(label)
