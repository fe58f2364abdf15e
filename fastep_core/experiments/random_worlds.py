"""Random solvable scenarios: circles, wall segments and U-shaped traps, 1-4 robots of either model.

    python -m fastep_core.experiments.random_worlds [SEED] [--family FAMILY]     (prints the scenario as YAML)

Why: hand-made scenarios show what their author thought of; a soak over random worlds finds what nobody did (a trap
the escape cannot leave, robots that deadlock). Each is a scenario mapping (docs/scenarios.md) validated by
`parse_scenario`, so it can be saved and rerun with `fastep-sim`. "Solvable" is decided by the exact planner: each
robot has a path keeping radius + clearance_margin from obstacles and border, robots parked at the other goals
counted as obstacles. A U-trap is three walls round a pocket facing a robot's start, across its line to the goal.
Families (`FAMILIES`, `random_family_data`; fastep-bench --families, docs/clutter.md): circle_field (one point mass,
50 x 50 m, 20-35 circles), circles_walls (10-20 circles, 4-10 walls, no traps), u_trap, multi_robot (2-4 robots),
tractor_trailer, diff_drive_walls and diff_drive_robots (those worlds with differential-drive bases at random
headings), and the v2 families of dynamic_worlds.py; the static five run when none is named. Benchmarks use seeds
FAMILY_SEED0 + k, far above the tests' (0-500), so no test or tuning has seen their worlds.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from fastep_core import cli
from fastep_core.errors import ParameterError
from fastep_core.experiments.dense_clutter import DENSE_FAMILIES, dense_clutter_data
from fastep_core.experiments.dynamic_worlds import DYNAMIC_FAMILIES, dynamic_family_data
from fastep_core.geometry import Circle
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.shortest_path.exact_path import solvable
from fastep_core.scenario import Scenario, parse_scenario
from fastep_core.world import World

__all__ = ['MODELS_MIX', 'ALL_FAMILIES', 'FAMILIES', 'FAMILY_SEED0', 'u_trap', 'u_trap_scenario_data',
           'circle_field_data', 'circles_walls_data', 'diff_drive_data', 'random_family_data', 'family_source',
           'parse_family_source',
           'random_scenario', 'random_scenario_data', 'solvable', 'main']

MODELS_MIX = 0.3
"""Share of tractor-trailers among random robots (the rest are point masses)."""
_ATTEMPTS = 200  # random layouts tried per scenario before giving up (a few are usually enough)
FAMILIES: tuple[str, ...] = ('circle_field', 'circles_walls', 'u_trap', 'multi_robot', 'tractor_trailer',
                             'diff_drive_walls', 'diff_drive_robots')
"""The static world families of random_family_data, in the order tables list them (the default benchmark)."""
ALL_FAMILIES: tuple[str, ...] = FAMILIES + DYNAMIC_FAMILIES + DENSE_FAMILIES
"""Every family random_family_data knows: the static ones, the v2 ones (dynamic_worlds.py) and dense clutter
(dense_clutter.py)."""
FAMILY_SEED0 = 1_000_000
"""First world seed of the families benchmark: disjoint from the seeds the tests use."""
FIELD_SIZE = 50.0   # metres: the square workspace of circle fields and circles + walls
CIRCLES = (20, 35)  # circles per circle field, drawn uniformly from this range


def u_trap(center: Sequence[float] | np.ndarray, width: float, depth: float, facing: float) -> list[dict[str, Any]]:
    """Three wall segments forming a U: the opening looks towards `facing` (radians), `width` across.

    `center` is the middle of the pocket; the back wall lies depth/2 behind it, away from the opening.
    """
    cx, cy = float(center[0]), float(center[1])
    ux, uy = math.cos(facing), math.sin(facing)     # towards the opening
    vx, vy = -uy, ux                                # across the pocket
    half_w, half_d = width / 2.0, depth / 2.0

    def point(along: float, across: float) -> list[float]:
        return [round(cx + ux * along + vx * across, 6), round(cy + uy * along + vy * across, 6)]

    back_left, back_right = point(-half_d, half_w), point(-half_d, -half_w)
    open_left, open_right = point(half_d, half_w), point(half_d, -half_w)
    return [{'segment': {'start': open_left, 'end': back_left}},
            {'segment': {'start': back_left, 'end': back_right}},
            {'segment': {'start': back_right, 'end': open_right}}]


def _robot(rng: np.random.Generator, name: str, start: np.ndarray, goal: np.ndarray,
           tractor: bool) -> dict[str, Any]:
    if not tractor:
        return {'name': name, 'model': 'point_mass', 'start': [round(float(v), 3) for v in start],
                'goal': [round(float(v), 3) for v in goal], 'radius': 0.5}
    # Headed roughly towards the goal, like the paper's application; the trailer in line.
    heading = math.atan2(goal[1] - start[1], goal[0] - start[0]) + float(rng.uniform(-0.5, 0.5))
    return {'name': name, 'model': 'tractor_trailer',
            'start': [round(float(start[0]), 3), round(float(start[1]), 3), round(heading, 6), round(heading, 6)],
            'goal': [round(float(v), 3) for v in goal], 'radius': 0.6, 'length': 1.0, 'trailer_length': 1.0,
            'width': 0.5}


def _layout(rng: np.random.Generator, n_robots: int, tractor_share: float) -> dict[str, Any]:
    width, height = (float(v) for v in rng.uniform(30.0, 50.0, 2))
    border = 3.0
    low, high = np.array([border, border]), np.array([width - border, height - border])
    robots: list[dict[str, Any]] = []
    ends: list[np.ndarray] = []   # every start and goal so far: robots keep 3 m apart at both
    for k in range(n_robots):
        for _ in range(50):
            start, goal = rng.uniform(low, high), rng.uniform(low, high)
            if np.hypot(*(goal - start)) < 0.5 * max(width, height):
                continue
            if all(np.hypot(*(p - q)) >= 3.0 for p in (start, goal) for q in ends):
                break
        else:
            continue
        ends += [start, goal]
        robots.append(_robot(rng, f'r{k + 1}', start, goal, bool(rng.random() < tractor_share)))
    obstacles: list[dict[str, Any]] = []
    # U-traps across some robots' straight runs, open towards the start, the goal behind the back wall.
    for robot in robots:
        if rng.random() >= 0.6:
            continue
        start, goal = np.array(robot['start'][:2]), np.array(robot['goal'])
        line = goal - start
        facing = math.atan2(-line[1], -line[0])
        trap_width, depth = float(rng.uniform(3.0, 9.0)), float(rng.uniform(2.0, 5.0))
        where = start + line * float(rng.uniform(0.35, 0.65))
        obstacles += u_trap(where, trap_width, depth, facing + float(rng.uniform(-0.3, 0.3)))
    for _ in range(int(rng.integers(3, 11))):
        centre = rng.uniform([0.0, 0.0], [width, height])
        obstacles.append({'circle': {'center': [round(float(v), 3) for v in centre],
                                     'radius': round(float(rng.uniform(0.5, 3.0)), 3)}})
    for _ in range(int(rng.integers(0, 4))):
        a = rng.uniform([0.0, 0.0], [width, height])
        angle, length = float(rng.uniform(0.0, math.pi)), float(rng.uniform(2.0, 8.0))
        b = a + length * np.array([math.cos(angle), math.sin(angle)])
        obstacles.append({'segment': {'start': [round(float(v), 3) for v in a],
                                      'end': [round(float(v), 3) for v in b]}})
    return {'workspace': [0.0, 0.0, round(width, 3), round(height, 3)], 'obstacles': obstacles, 'robots': robots}


def _clear_of_robots(data: dict[str, Any], margin: float) -> list[dict[str, Any]]:
    """Drop the obstacles that come within a robot's clearance (plus half a metre) of a start or goal."""
    ends = np.array([p for r in data['robots'] for p in (r['start'][:2], r['goal'])], dtype=float)
    reach = np.array([r['radius'] + margin + 0.5 for r in data['robots'] for _ in (0, 1)])
    kept = []
    for item in data['obstacles']:
        world = World.from_obstacles(data['workspace'], [_parse_obstacle(item)])
        if np.all(world.obstacles.clearance(ends) >= reach):
            kept.append(item)
    return kept


def _parse_obstacle(item: dict[str, Any]) -> Any:
    from fastep_core.geometry import Segment
    if 'circle' in item:
        return Circle(tuple(item['circle']['center']), item['circle']['radius'])
    return Segment(tuple(item['segment']['start']), tuple(item['segment']['end']))


def random_scenario_data(seed: int, *, n_robots: int | None = None,
                         tractor_share: float = MODELS_MIX) -> dict[str, Any]:
    """The scenario mapping of random scenario `seed` (same seed, same scenario), solvable by construction.

    n_robots: 1-4, drawn when None. Raises RuntimeError if no solvable layout turns up (has not happened).
    """
    if n_robots is not None and not 1 <= n_robots <= 4:
        raise ParameterError(f'n_robots must be 1-4, got {n_robots}')
    rng = np.random.default_rng(seed)
    margin = PlannerParams().clearance_margin
    for _ in range(_ATTEMPTS):
        count = int(rng.integers(1, 5)) if n_robots is None else n_robots
        data = _layout(rng, count, tractor_share)
        if len(data['robots']) < count:
            continue
        data['obstacles'] = _clear_of_robots(data, margin)
        data = {'name': f'random_{seed}',
                'description': f'random scenario {seed}: {len(data["robots"])} robot(s), '
                               f'{len(data["obstacles"])} obstacle(s)', **data}
        if solvable(parse_scenario(data)):
            return data
    raise RuntimeError(f'no solvable layout for random scenario {seed} in {_ATTEMPTS} attempts')


def u_trap_scenario_data(seed: int, model: str = 'point_mass') -> dict[str, Any]:
    """One robot and one U-shaped trap across its straight line, open towards it (and a few circles away
    from that line): the trap-escape benchmark's scenarios. Same seed, same scenario."""
    if model not in ('point_mass', 'tractor_trailer'):
        raise ParameterError(f'model must be point_mass or tractor_trailer, got {model!r}')
    rng = np.random.default_rng(seed)
    margin = PlannerParams().clearance_margin
    for _ in range(_ATTEMPTS):
        width, height = (float(v) for v in rng.uniform(30.0, 45.0, 2))
        angle = float(rng.uniform(-math.pi, math.pi))
        centre = np.array([width, height]) / 2.0
        reach = 0.4 * min(width, height)
        way = np.array([math.cos(angle), math.sin(angle)])
        start, goal = centre - reach * way, centre + reach * way
        trap_width, depth = float(rng.uniform(3.0, 9.0)), float(rng.uniform(2.0, 5.0))
        facing = angle + math.pi + float(rng.uniform(-0.3, 0.3))
        obstacles = u_trap(centre + way * float(rng.uniform(-1.0, 1.0)), trap_width, depth, facing)
        for _ in range(int(rng.integers(0, 6))):
            c = rng.uniform([0.0, 0.0], [width, height])
            if float(np.hypot(*(c - centre))) > 7.0:   # clear of the trap
                obstacles.append({'circle': {'center': [round(float(v), 3) for v in c],
                                             'radius': round(float(rng.uniform(0.5, 2.0)), 3)}})
        data = {'name': f'u_trap_{seed}', 'description': f'U-trap scenario {seed} ({model})',
                'workspace': [0.0, 0.0, round(width, 3), round(height, 3)],
                'obstacles': obstacles, 'robots': [_robot(rng, 'r1', start, goal, model == 'tractor_trailer')]}
        data['obstacles'] = _clear_of_robots(data, margin)
        if len(data['obstacles']) >= 3 and solvable(parse_scenario(data)):
            return data
    raise RuntimeError(f'no solvable U-trap layout for seed {seed}')


def circle_field_data(seed: int, circles: tuple[int, int] = CIRCLES) -> dict[str, Any]:
    """A solvable 50 x 50 m field of `circles` (low, high) circles of radius 0.5-2.5 m placed uniformly, one
    point mass whose start and goal are uniform in [3, 47]^2 and at least 35 m apart; circles too close to the
    start or goal dropped. Its generator is seeded 10_000 + seed (seeds 0-15: the worlds benchmarks.clutter_diagnosis
    measured the activation policy on, docs/architecture.md); same seed, same world."""
    rng = np.random.default_rng(10_000 + seed)
    margin = PlannerParams().clearance_margin
    for _ in range(_ATTEMPTS):
        start, goal = _far_apart(rng)
        obstacles = [_circle(rng.uniform(0.0, FIELD_SIZE, 2), float(rng.uniform(0.5, 2.5)))
                     for _ in range(int(rng.integers(circles[0], circles[1] + 1)))]
        data: dict[str, Any] = {'name': f'circle_field_{seed}', 'workspace': [0.0, 0.0, FIELD_SIZE, FIELD_SIZE],
                                'obstacles': obstacles, 'robots': [_robot(rng, 'r1', start, goal, False)]}
        data['obstacles'] = _clear_of_robots(data, margin)
        data['description'] = f'circle field {seed}: {len(data["obstacles"])} circles'
        if solvable(parse_scenario(data)):
            return data
    raise RuntimeError(f'no solvable circle field for seed {seed}')


def circles_walls_data(seed: int) -> dict[str, Any]:
    """A solvable 50 x 50 m world of 10-20 circles (radius 0.5-2.5 m) and 4-10 straight walls (2-10 m long,
    any direction) placed uniformly, one point mass as in circle_field_data; same seed, same world."""
    rng = np.random.default_rng(20_000 + seed)
    margin = PlannerParams().clearance_margin
    for _ in range(_ATTEMPTS):
        start, goal = _far_apart(rng)
        obstacles = [_circle(rng.uniform(0.0, FIELD_SIZE, 2), float(rng.uniform(0.5, 2.5)))
                     for _ in range(int(rng.integers(10, 21)))]
        for _ in range(int(rng.integers(4, 11))):
            a = rng.uniform(0.0, FIELD_SIZE, 2)
            angle, length = float(rng.uniform(0.0, math.pi)), float(rng.uniform(2.0, 10.0))
            b = a + length * np.array([math.cos(angle), math.sin(angle)])
            obstacles.append({'segment': {'start': [round(float(v), 3) for v in a],
                                          'end': [round(float(v), 3) for v in b]}})
        data: dict[str, Any] = {'name': f'circles_walls_{seed}', 'workspace': [0.0, 0.0, FIELD_SIZE, FIELD_SIZE],
                                'obstacles': obstacles, 'robots': [_robot(rng, 'r1', start, goal, False)]}
        data['obstacles'] = _clear_of_robots(data, margin)
        data['description'] = f'circles and walls {seed}: {len(data["obstacles"])} obstacles'
        if solvable(parse_scenario(data)):
            return data
    raise RuntimeError(f'no solvable circles-and-walls world for seed {seed}')


def diff_drive_data(data: dict[str, Any], seed: int) -> dict[str, Any]:
    """`data` with every robot a differential-drive base at its start position, facing a heading drawn
    uniformly in [-pi, pi) from a generator of its own (seeded 30_000 + seed: the world is the one `data` is).
    The radius stays: a smaller one would only make the world easier, and the same radius compares the base
    with the point mass on the same worlds."""
    rng = np.random.default_rng(30_000 + seed)
    robots = []
    for robot in data['robots']:
        x, y = robot['start'][:2]
        robots.append({'name': robot['name'], 'model': 'diff_drive',
                       'start': [x, y, round(float(rng.uniform(-math.pi, math.pi)), 6)],
                       'goal': robot['goal'], 'radius': robot['radius']})
    return {**data, 'robots': robots, 'description': f'{data.get("description", "")} (differential drive)'}


def _far_apart(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A start and a goal uniform in the field less a 3 m border, at least 35 m apart."""
    while True:
        start, goal = rng.uniform(3.0, FIELD_SIZE - 3.0, 2), rng.uniform(3.0, FIELD_SIZE - 3.0, 2)
        if np.hypot(*(goal - start)) >= 35.0:
            return start, goal


def _circle(centre: np.ndarray, radius: float) -> dict[str, Any]:
    return {'circle': {'center': [round(float(v), 3) for v in centre], 'radius': round(radius, 3)}}


def random_family_data(family: str, seed: int) -> dict[str, Any]:
    """The scenario mapping of world `seed` of a family (one of FAMILIES; see the module docstring), named
    FAMILY_SEED, solvable; same family and seed, same world."""
    if family == 'circle_field':
        data = circle_field_data(seed)
    elif family == 'circles_walls':
        data = circles_walls_data(seed)
    elif family == 'u_trap':
        data = u_trap_scenario_data(seed)
    elif family == 'multi_robot':
        count = int(np.random.default_rng(seed).integers(2, 5))
        data = random_scenario_data(seed, n_robots=count)
    elif family == 'tractor_trailer':
        data = random_scenario_data(seed, n_robots=1, tractor_share=1.0)
    elif family == 'diff_drive_walls':
        data = diff_drive_data(circles_walls_data(seed), seed)
    elif family == 'diff_drive_robots':
        count = int(np.random.default_rng(seed).integers(1, 5))
        data = diff_drive_data(random_scenario_data(seed, n_robots=count, tractor_share=0.0), seed)
    elif family in DYNAMIC_FAMILIES:
        data = dynamic_family_data(family, seed)
    elif family in DENSE_FAMILIES:
        data = dense_clutter_data(seed, on_map=family == 'dense_clutter', footprint=family == 'dense_clutter_jackal')
    else:
        raise ParameterError(f'unknown world family {family!r}; choose one of {", ".join(ALL_FAMILIES)}')
    return {**data, 'name': f'{family}_{seed}'}


def family_source(family: str, seed: int) -> str:
    """The source name of a family world, 'FAMILY:SEED' (e.g. 'u_trap:1000004'): what
    fastep_core.experiments.batches.cached_scenario loads, and what tables and records call it."""
    return f'{family}:{seed}'


def parse_family_source(source: str) -> tuple[str, int] | None:
    """(family, seed) of a family_source name; None for anything else (a built-in name or a file path)."""
    family, colon, seed = source.partition(':')
    if not colon or family not in ALL_FAMILIES or not seed.isdigit():
        return None
    return family, int(seed)


def random_scenario(seed: int, *, n_robots: int | None = None, tractor_share: float = MODELS_MIX) -> Scenario:
    """Random scenario `seed`, validated (see random_scenario_data)."""
    return parse_scenario(random_scenario_data(seed, n_robots=n_robots, tractor_share=tractor_share))


def main(argv: Sequence[str] | None = None) -> int:
    """Print random scenario SEED (default 0), or world SEED of a family, as YAML, ready for `fastep-sim FILE`."""
    import yaml

    prog = 'python -m fastep_core.experiments.random_worlds'
    parser = cli.Parser(prog=prog, description='Print a random solvable scenario as YAML.')
    parser.add_argument('seed', nargs='?', type=cli.seed, default=0, help='scenario seed (default 0)')
    parser.add_argument('--family', choices=ALL_FAMILIES,
                        help='a world of this family (the families benchmark\'s worlds are seeds 1000000 on)')

    def run() -> int:
        args = parser.parse_args(argv)
        data = random_scenario_data(args.seed) if args.family is None else random_family_data(args.family, args.seed)
        print(yaml.safe_dump(data, sort_keys=False), end='')
        return 0
    return cli.guard(prog, run)


if __name__ == '__main__':
    raise SystemExit(main())
