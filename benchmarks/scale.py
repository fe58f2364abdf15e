"""Benchmark: how run time and memory grow with the number of robots and of obstacles.

    python -m benchmarks.scale robots [--counts 10 20 40 100] [--seed 0] [--max-sim-time 300]
    python -m benchmarks.scale obstacles [--counts 200 500 1000] [--side 50] [--seed 0]
    python -m benchmarks.scale maps [--worlds office ...]

robots: one in-process `simulate` (what `fastep-sim` runs) of N point-mass robots in a square world of side
max(50, 10 sqrt(N)) m with N / 2 random circles, fixed seeds. Prints wall and CPU time, simulated time,
arrivals and collisions per N.

obstacles: the exact shortest path (fastep_core.planning.shortest_path.optimal.shortest_path) from (2, 2) to the far
corner through N random circles in a square of side --side. Prints wall and CPU time, peak traced memory
(tracemalloc), the size of the search graph and the path length.

maps: the exact shortest path from start to goal of the robot harness's worlds (fastep_testing/robot_worlds.py)
in their 0.05 m /map as the planner node reads it (the occupied cells' outline), clearance radius + margin: the
circles the search keeps (each corner's cap once, none blocked all round) against every wall end's cap, in one run.

Wall times depend on the machine's load: the script prints the load average to go with the numbers.
"""

from __future__ import annotations

import argparse
import math
import os
import time
import tracemalloc
from typing import Any

import numpy as np

from fastep_core.geometry import Circle
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.scenario import parse_scenario
from fastep_core.simulator import simulate
from fastep_core.world import World


def load_text() -> str:
    one, five, fifteen = os.getloadavg()
    return f'load average {one:.2f}, {five:.2f}, {fifteen:.2f}'


def crowd_scenario_data(n_robots: int, seed: int, max_sim_time: float) -> dict[str, Any]:
    """N point-mass robots and N / 2 circles in a square world (the scenario mapping of docs/scenarios.md)."""
    rng = np.random.default_rng(seed)
    side = round(max(50.0, 10.0 * math.sqrt(n_robots)), 3)
    border = 3.0
    ends: list[np.ndarray] = []
    robots = []
    while len(robots) < n_robots:
        start, goal = rng.uniform(border, side - border, 2), rng.uniform(border, side - border, 2)
        if np.hypot(*(goal - start)) < 0.5 * side:
            continue
        if any(np.hypot(*(p - q)) < 3.0 for p in (start, goal) for q in ends):
            continue
        ends += [start, goal]
        robots.append({'name': f'r{len(robots) + 1}', 'model': 'point_mass', 'radius': 0.5,
                       'start': [round(float(v), 3) for v in start], 'goal': [round(float(v), 3) for v in goal]})
    points = np.array(ends)
    obstacles = []
    while len(obstacles) < n_robots // 2:
        centre, radius = rng.uniform(0.0, side, 2), float(rng.uniform(0.5, 2.0))
        if np.min(np.hypot(*(points - centre).T)) - radius < 0.5 + 0.2 + 0.5:   # radius + margin + 0.5 m
            continue
        obstacles.append({'circle': {'center': [round(float(v), 3) for v in centre], 'radius': round(radius, 3)}})
    return {'name': f'crowd_{n_robots}_{seed}', 'workspace': [0.0, 0.0, side, side], 'obstacles': obstacles,
            'robots': robots, 'planner': {'max_sim_time': max_sim_time}}


def cluttered_world(n: int, side: float, seed: int) -> World:
    rng = np.random.default_rng(seed)
    circles: list[Circle] = []
    while len(circles) < n:
        c, r = rng.uniform(0.0, side, 2), float(rng.uniform(0.2, 0.8))
        if min(math.dist(c, (2.0, 2.0)), math.dist(c, (side - 2.0, side - 2.0))) > r + 1.5:
            circles.append(Circle((float(c[0]), float(c[1])), r))
    return World((0.0, 0.0, side, side), tuple(circles))


def bench_robots(counts: list[int], seed: int, max_sim_time: float, min_approach_speed: float | None = None) -> None:
    print(load_text())
    print(f'{"robots":>6} {"wall s":>8} {"CPU s":>8} {"sim s":>8} {"arrived":>8} {"collided":>8}')
    for n in counts:
        data = crowd_scenario_data(n, seed, max_sim_time)
        if min_approach_speed is not None:   # e.g. 0: the paper's gains (docs/approach_speed.md)
            data.setdefault('planner', {})['min_approach_speed'] = min_approach_speed
        scenario = parse_scenario(data)
        start, cpu = time.perf_counter(), time.process_time()
        run = simulate(scenario, 'fastep', seed)
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        sim = max((r.sim_time or max_sim_time) for r in run.robots)
        print(f'{n:>6} {wall:>8.1f} {cpu:>8.1f} {sim:>8.1f} {sum(r.reached for r in run.robots):>8} '
              f'{sum(r.collided for r in run.robots):>8}', flush=True)
    print(load_text())


def bench_obstacles(counts: list[int], side: float, seed: int) -> None:
    print(load_text())
    print(f'{"circles":>7} {"wall s":>8} {"CPU s":>8} {"peak MB":>8} {"nodes":>7} {"edges":>8} {"length m":>9}')
    for n in counts:
        world = cluttered_world(n, side, seed)
        tracemalloc.start()
        start, cpu = time.perf_counter(), time.process_time()
        path = shortest_path(world, (2.0, 2.0), (side - 2.0, side - 2.0), 0.6)
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        nodes, edges, length = ('-', '-', 'no path') if path is None else \
            (path.nodes, path.edges, f'{path.length:.3f}')
        print(f'{n:>7} {wall:>8.2f} {cpu:>8.2f} {peak / 1e6:>8.0f} {nodes:>7} {edges:>8} {length:>9}', flush=True)
    print(load_text())


def bench_maps(names: list[str]) -> None:
    from benchmarks.scan_perception import grid_map
    from fastep_core.planning.shortest_path import optimal
    from fastep_testing.robot_worlds import WORLDS
    print(load_text())
    print(f'{"world":>14} {"walls":>6} {"caps":>9} {"circles":>8} {"wall s":>8} {"every cap s":>12} {"ratio":>6} '
          f'{"same path":>9}')
    kept = optimal._Problem._add_caps
    for name in names:
        scenario = WORLDS[name]
        robot = scenario.robots[0]
        world = grid_map(scenario)
        clearance = robot.radius + scenario.planner.clearance_margin
        times, paths, circles = [], [], []
        for every in (False, True):
            if every:   # the search as it was: every wall end's cap
                optimal._Problem._add_caps = lambda self, caps: self.circles.extend(caps)  # type: ignore[method-assign]  # the comparison
            try:
                start = time.perf_counter()
                paths.append(shortest_path(world, robot.start[:2], robot.goal, clearance))
                times.append(time.perf_counter() - start)
                circles.append(len(optimal._Problem(world, clearance, clearance).circles))
            finally:
                optimal._Problem._add_caps = kept  # type: ignore[method-assign]  # restored
        same = paths[0] is not None and paths[1] is not None and np.array_equal(paths[0].points, paths[1].points)
        walls = len(world.obstacle_list)
        print(f'{name:>14} {walls:>6} {circles[1]:>9} {circles[0]:>8} {times[0]:>8.3f} {times[1]:>12.3f} '
              f'{times[1] / times[0]:>6.1f} {str(same):>9}', flush=True)
    print(load_text())


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='python -m benchmarks.scale', description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest='what', required=True)
    robots = sub.add_parser('robots', help='one fastep-sim run of N robots')
    robots.add_argument('--counts', type=int, nargs='+', default=[10, 20, 40, 100])
    robots.add_argument('--seed', type=int, default=0)
    robots.add_argument('--max-sim-time', type=float, default=300.0)
    robots.add_argument('--min-approach-speed', type=float, default=None,
                        help='planner min_approach_speed (m/s; default: the planner default; 0: the paper\'s gains)')
    obstacles = sub.add_parser('obstacles', help='the exact shortest path among N circles')
    obstacles.add_argument('--counts', type=int, nargs='+', default=[200, 500, 1000])
    obstacles.add_argument('--side', type=float, default=50.0)
    obstacles.add_argument('--seed', type=int, default=0)
    maps = sub.add_parser('maps', help="the exact path across the robot harness's worlds' /map outlines")
    maps.add_argument('--worlds', nargs='+', default=['open_room', 'behind_wall', 'unmapped_box', 'thin_cylinders',
                                                      'office'])
    args = p.parse_args(argv)
    if args.what == 'robots':
        bench_robots(args.counts, args.seed, args.max_sim_time, args.min_approach_speed)
    elif args.what == 'maps':
        bench_maps(args.worlds)
    else:
        bench_obstacles(args.counts, args.side, args.seed)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
