"""Random v2 worlds for the families benchmark: crossing movers, unknown obstacles, misplaced obstacles, and
all three at once with 2-4 robots. Every robot carries a laser scanner (SENSOR).

Each world is a 50 x 50 m field of known still circles and what its family adds: crossing_movers (2-4 movers
going back and forth across a point mass's straight run, known or not), unknown_obstacles (circles and walls
near the run that are not on the map), misplaced_obstacles (every obstacle on the map displaced by
position_sigma 0.3-1.0 m), dynamic_mix (2-4 robots with some of each). The exact sizes are in the code below and
docs/dynamic_world.md.

Solvable from the truth: every robot has an exact path keeping radius + clearance_margin from every still
obstacle where it really is. Movers' tracks and misplaced obstacles keep clear of every start and goal, so a
robot's goal is never refused on the map. Same family and seed, same world: each family's Generator is seeded
FAMILY_OFFSET[family] + seed.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fastep_core.geometry import Circle, Segment, point_segment_distance
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.shortest_path.exact_path import solvable
from fastep_core.scenario import parse_scenario
from fastep_core.world import World

__all__ = ['DYNAMIC_FAMILIES', 'FAMILY_OFFSET', 'SENSOR', 'dynamic_family_data']

DYNAMIC_FAMILIES: tuple[str, ...] = ('crossing_movers', 'unknown_obstacles', 'misplaced_obstacles', 'dynamic_mix')
FAMILY_OFFSET = {'crossing_movers': 30_000, 'unknown_obstacles': 40_000, 'misplaced_obstacles': 50_000,
                 'dynamic_mix': 60_000}
SENSOR: dict[str, Any] = {'range': 8.0, 'fov': 6.2832, 'beams': 360, 'noise': 0.01}
"""Every family robot's scanner: an 8 m, 360-beam full-turn lidar with 1 cm noise."""
FIELD = 50.0
RADIUS = 0.5          # the point masses' radius
_ATTEMPTS = 200


def _pt(p: np.ndarray) -> list[float]:
    return [round(float(p[0]), 3), round(float(p[1]), 3)]


def _robots(rng: np.random.Generator, count: int, apart: float) -> list[dict[str, Any]]:
    """`count` point masses with a sensor, start and goal >= `apart` m apart and 3 m from the others' ends."""
    robots: list[dict[str, Any]] = []
    ends: list[np.ndarray] = []
    while len(robots) < count:
        start, goal = rng.uniform(3.0, FIELD - 3.0, 2), rng.uniform(3.0, FIELD - 3.0, 2)
        if np.hypot(*(goal - start)) < apart or any(np.hypot(*(p - q)) < 3.0 for p in (start, goal) for q in ends):
            continue
        ends += [start, goal]
        robots.append({'name': f'r{len(robots) + 1}', 'model': 'point_mass', 'start': _pt(start), 'goal': _pt(goal),
                       'radius': RADIUS, 'sensor': dict(SENSOR)})
    return robots


def _ends(robots: list[dict[str, Any]]) -> np.ndarray:
    return np.array([p for r in robots for p in (r['start'], r['goal'])], dtype=float)


def _near_run(rng: np.random.Generator, robot: dict[str, Any], spread: float) -> np.ndarray:
    """A point near the robot's straight run: 20-80 % of the way, `spread` m standard deviation across it."""
    start, goal = np.array(robot['start'], dtype=float), np.array(robot['goal'], dtype=float)
    run = goal - start
    across = np.array([-run[1], run[0]]) / np.hypot(*run)
    point: np.ndarray = start + run * float(rng.uniform(0.2, 0.8)) + across * float(rng.normal(0.0, spread))
    return point


def _circle(centre: np.ndarray, radius: float, **keys: Any) -> dict[str, Any]:
    return {'circle': {'center': _pt(centre), 'radius': round(radius, 3)}, **keys}


def _wall_across(rng: np.random.Generator, robot: dict[str, Any], **keys: Any) -> dict[str, Any]:
    """A 3-8 m wall near the robot's run, within 0.5 rad of square to it."""
    centre = _near_run(rng, robot, 1.5)
    start, goal = np.array(robot['start']), np.array(robot['goal'])
    angle = math.atan2(*(goal - start)[::-1]) + math.pi / 2 + float(rng.uniform(-0.5, 0.5))
    half = 0.5 * float(rng.uniform(3.0, 8.0)) * np.array([math.cos(angle), math.sin(angle)])
    return {'segment': {'start': _pt(centre - half), 'end': _pt(centre + half)}, **keys}


def _mover(rng: np.random.Generator, robot: dict[str, Any], ends: np.ndarray, known: bool) -> dict[str, Any] | None:
    """A mover going back and forth across the robot's run (module docstring); None if its track would come
    near a robot's start or goal or leave the field."""
    radius, speed = float(rng.uniform(0.4, 1.2)), float(rng.uniform(0.3, 0.8))
    crossing = _near_run(rng, robot, 0.0)
    start, goal = np.array(robot['start']), np.array(robot['goal'])
    angle = math.atan2(*(goal - start)[::-1]) + math.pi / 2 + float(rng.uniform(-0.5, 0.5))
    half = 0.5 * float(rng.uniform(12.0, 24.0))
    direction = np.array([math.cos(angle), math.sin(angle)]) * (1.0 if rng.random() < 0.5 else -1.0)
    a, b = crossing - half * direction, crossing + half * direction
    if min(a.min(), b.min()) < radius or max(a.max(), b.max()) > FIELD - radius:
        return None
    if point_segment_distance(ends, a, b).min() < radius + RADIUS + 1.5:
        return None
    # Starting anywhere along its track (not at an end), so movers are not all in phase.
    begin = a + (b - a) * float(rng.uniform(0.0, 1.0))
    return {'circle': {'center': _pt(begin), 'radius': round(radius, 3)},
            'motion': {'waypoints': [_pt(b), _pt(a)], 'speed': round(speed, 3)}, 'known': known}


def _shape(item: dict[str, Any]) -> Circle | Segment:
    if 'circle' in item:
        return Circle(tuple(item['circle']['center']), item['circle']['radius'])
    return Segment(tuple(item['segment']['start']), tuple(item['segment']['end']))


def _keep_clear(obstacles: list[dict[str, Any]], robots: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Still obstacles kept only when clear of every start and goal (radius + margin + 0.5 m, plus 3 sigma of a
    misplaced one) and of every mover's track (a mover's radius + 1 m: movers do not pass through them)."""
    margin = PlannerParams().clearance_margin
    ends = _ends(robots)
    movers = [o for o in obstacles if 'motion' in o]
    tracks = [(np.array(m['motion']['waypoints'][0]), np.array(m['motion']['waypoints'][1]), m['circle']['radius'])
              for m in movers]
    kept = [*movers]
    for item in obstacles:
        if 'motion' in item:
            continue
        world = World((0.0, 0.0, FIELD, FIELD), (_shape(item),))
        reach = RADIUS + margin + 0.5 + 3.0 * float(item.get('position_sigma', 0.0))
        if world.obstacles.clearance(ends).min() < reach:
            continue
        if any(world.obstacles.path_distances(a, b).min() < r + 1.0 for a, b, r in tracks):
            continue
        kept.append(item)
    return kept


def _known_circles(rng: np.random.Generator, low: int, high: int) -> list[dict[str, Any]]:
    return [_circle(rng.uniform(0.0, FIELD, 2), float(rng.uniform(0.5, 2.5)))
            for _ in range(int(rng.integers(low, high + 1)))]


def _layout(family: str, rng: np.random.Generator) -> dict[str, Any]:
    if family == 'dynamic_mix':
        robots = _robots(rng, int(rng.integers(2, 5)), 25.0)
    else:
        robots = _robots(rng, 1, 35.0)
    ends = _ends(robots)
    obstacles = _known_circles(rng, 8, 15)
    if family == 'crossing_movers':
        for _ in range(int(rng.integers(2, 5))):
            mover = _mover(rng, robots[0], ends, bool(rng.random() < 0.5))
            if mover is not None:
                obstacles.append(mover)
    elif family == 'unknown_obstacles':
        obstacles += [_circle(_near_run(rng, robots[0], 2.0), float(rng.uniform(0.5, 2.0)), known=False)
                      for _ in range(int(rng.integers(3, 7)))]
        obstacles += [_wall_across(rng, robots[0], known=False) for _ in range(int(rng.integers(1, 3)))]
    elif family == 'misplaced_obstacles':
        obstacles += [_circle(_near_run(rng, robots[0], 2.0), float(rng.uniform(0.5, 2.0)))
                      for _ in range(int(rng.integers(3, 7)))]
        obstacles += [_wall_across(rng, robots[0]) for _ in range(int(rng.integers(2, 6)))]
        for item in obstacles:
            item['position_sigma'] = round(float(rng.uniform(0.3, 1.0)), 3)
    else:   # dynamic_mix
        for item in obstacles:
            if rng.random() < 1.0 / 3.0:
                item['position_sigma'] = round(float(rng.uniform(0.3, 1.0)), 3)
        for _ in range(int(rng.integers(1, 4))):
            mover = _mover(rng, robots[int(rng.integers(len(robots)))], ends, bool(rng.random() < 0.5))
            if mover is not None:
                obstacles.append(mover)
        obstacles += [_circle(_near_run(rng, robots[int(rng.integers(len(robots)))], 2.0),
                              float(rng.uniform(0.5, 2.0)), known=False) for _ in range(int(rng.integers(2, 5)))]
    return {'workspace': [0.0, 0.0, FIELD, FIELD], 'obstacles': _keep_clear(obstacles, robots), 'robots': robots}


def dynamic_family_data(family: str, seed: int) -> dict[str, Any]:
    """The scenario mapping of world `seed` of a v2 family (module docstring), solvable from the truth."""
    rng = np.random.default_rng(FAMILY_OFFSET[family] + seed)
    for _ in range(_ATTEMPTS):
        data = _layout(family, rng)
        if family in ('crossing_movers', 'dynamic_mix') and not any('motion' in o for o in data['obstacles']):
            continue
        counts = {'movers': sum('motion' in o for o in data['obstacles']),
                  'unknown': sum(o.get('known') is False and 'motion' not in o for o in data['obstacles']),
                  'misplaced': sum('position_sigma' in o for o in data['obstacles'])}
        data = {'name': f'{family}_{seed}',
                'description': f'{family} {seed}: {len(data["robots"])} robot(s), {len(data["obstacles"])} obstacles '
                               f'({", ".join(f"{v} {k}" for k, v in counts.items() if v)})', **data}
        if solvable(parse_scenario(data)):
            return data
    raise RuntimeError(f'no solvable {family} world for seed {seed}')
