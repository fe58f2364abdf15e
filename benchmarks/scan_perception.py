"""Benchmark: perception of one 720-beam 270-degree scan, as a robot's planner does it, and the phantoms it sees.

Each case drives a robot along its exact shortest path at 1 m/s with a 720-beam 270-degree laser (10 m, noise
0.01 m) scanning the true world at 20 Hz, and times Perception.update on every scan, the robot planning in a map
it was given: `dense_clutter_laser`, the first worlds of the dense-clutter family, each driven by FAStep-Route
(nothing on the map); the robot harness's worlds, the laser 0.25 m ahead of the base's centre and the map a 0.05 m
occupancy grid read as the planner node reads /map; `floor`, 60 m x 40 m of 44 rooms off two corridors.
Per case: scans, median, p99 and max wall time per scan (ms), the p99 of its thread CPU time (what a loaded
machine's preemptions leave out), and the phantoms: every world is still, so each track perception called a mover
is one (distinct tracks, and the most at once). Target: p99 <= 2 ms.

Run: `.venv/bin/python -m benchmarks.scan_perception [--clutter-worlds N] [--cases NAME ...]`.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from typing import Any, Callable, Iterator

import numpy as np

from fastep_core.dynamic_world import DynamicWorld, map_generator
from fastep_core.experiments.batches import cached_scenario
from fastep_core.experiments.random_worlds import family_source
from fastep_core.geometry import Segment
from fastep_core.perception import belief as belief_module
from fastep_core.perception.belief import Perception
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.scenario import Scenario, parse_scenario
from fastep_core.sensing.laser import LaserSpec
from fastep_core.simulator import simulate
from fastep_core.world import World
from fastep_testing.robot_worlds import WORLDS
from msg_tools.convert import occupancy_grid_obstacles, world_to_occupancy_grid

LASER = LaserSpec(10.0, 1.5 * math.pi, 720, 0.01, (0.25, 0.0, 0.0))
SCAN_PERIOD = 0.05
SPEED = 1.0


def floor() -> Scenario:
    """Two corridors along x with rooms of 5 m x 6 m on both sides of each, doors 1 m wide onto the corridor, and
    a hall along the east wall joining the corridors."""
    width, height, room, depth, door = 60.0, 40.0, 5.0, 6.0, 1.0
    walls: list[dict[str, Any]] = []

    def wall(a: tuple[float, float], b: tuple[float, float]) -> None:
        walls.append({'segment': {'start': list(a), 'end': list(b)}})
    for a, b in (((0.5, 0.5), (59.5, 0.5)), ((59.5, 0.5), (59.5, 39.5)), ((59.5, 39.5), (0.5, 39.5)),
                 ((0.5, 39.5), (0.5, 0.5))):
        wall(a, b)
    rooms = int((width - 5.0) // room)                  # a 4 m hall at the east end joins the corridors
    for corridor in (10.0, 30.0):                       # each corridor 2 m wide, centred at y = corridor
        for side, y in ((-1, corridor - 1.0), (1, corridor + 1.0)):
            far = y + side * depth
            wall((0.5, far), (0.5 + rooms * room, far))
            for k in range(rooms):
                x0 = 0.5 + k * room
                wall((x0, y), (x0, far))                # the wall between two rooms
                wall((x0, y), (x0 + 1.5, y))            # the corridor wall, a door from x0 + 1.5 to x0 + 2.5
                wall((x0 + 1.5 + door, y), (x0 + room, y))
    return parse_scenario({'name': 'floor', 'workspace': [0.0, 0.0, width, height], 'obstacles': walls,
                           'robots': [{'name': 'r1', 'model': 'diff_drive', 'start': [3.0, 5.5, 0.0],
                                       'goal': [3.0, 34.5], 'radius': 0.3}]})


def grid_map(scenario: Scenario) -> World:
    """What the planner node believes from a 0.05 m /map of the known world: the occupied cells' outline."""
    known = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs).planner_map(map_generator(0)).world
    grid = world_to_occupancy_grid(known, 0.05)
    return World(scenario.world.workspace, tuple(occupancy_grid_obstacles(grid)))


def drive(scenario: Scenario) -> Iterator[tuple[float, tuple[float, float, float]]]:
    """(t, robot pose) every SCAN_PERIOD along the robot's exact shortest path in the truth, at SPEED."""
    robot = scenario.robots[0]
    path = shortest_path(scenario.world, robot.start[:2], robot.goal, robot.radius + 0.1)
    if path is None:
        raise SystemExit(f'{scenario.name}: no path')
    points = path.sample(SPEED * SCAN_PERIOD)
    for k in range(1, len(points)):
        d = points[k] - points[k - 1]
        yield k * SCAN_PERIOD, (float(points[k][0]), float(points[k][1]), math.atan2(d[1], d[0]))


def timed_walk(scenario: Scenario) -> tuple[list[tuple[float, float]], set[str], int]:
    """(Wall, thread CPU) seconds of each Perception.update along the walk, the movers' names, the most at once."""
    truth = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs)
    perception = Perception(LASER, grid_map(scenario))
    rng = np.random.default_rng(0)
    times: list[tuple[float, float]] = []
    names: set[str] = set()
    most = 0
    for t, pose in drive(scenario):
        scanner = LASER.pose_on(pose)
        reading = truth.scan(LASER, scanner, t, rng)
        began, cpu = time.perf_counter(), time.thread_time()
        belief = perception.update(t, scanner, reading)
        times.append((time.perf_counter() - began, time.thread_time() - cpu))
        names.update(m.name for m in belief.movers)
        most = max(most, len(belief.movers))
    return times, names, most


def timed_clutter(worlds: int) -> tuple[list[tuple[float, float]], set[str], int]:
    """Perception.update's (wall, thread CPU) seconds in FAStep-Route's runs of the first dense_clutter_laser
    worlds."""
    times: list[tuple[float, float]] = []
    names: set[str] = set()
    most = [0]
    update: Callable[..., Any] = Perception.update

    def timed(self: Perception, *args: Any, **kwargs: Any) -> Any:
        began, cpu = time.perf_counter(), time.thread_time()
        out = update(self, *args, **kwargs)
        times.append((time.perf_counter() - began, time.thread_time() - cpu))
        names.update(f'{id(self)} {m.name}' for m in out.movers)
        most[0] = max(most[0], len(out.movers))
        return out
    belief_module.Perception.update = timed   # type: ignore[method-assign]  # timed for the benchmark, restored below
    try:
        for k in range(worlds):
            simulate(cached_scenario(family_source('dense_clutter_laser', 1_000_000 + k)), 'fastep_route', 0)
    finally:
        belief_module.Perception.update = update   # type: ignore[method-assign]  # the method as it was
    return times, names, most[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    cases = ['dense_clutter_laser', *WORLDS, 'floor']
    parser.add_argument('--cases', nargs='+', choices=cases, default=cases)
    parser.add_argument('--clutter-worlds', type=int, default=10, help='dense_clutter_laser worlds (default 10)')
    args = parser.parse_args()
    print(f'load average at the start: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')
    print('| case | map segments | scans | median ms | p99 ms | max ms | p99 CPU ms | phantom movers | most at once |')
    print('|---|---|---|---|---|---|---|---|---|')
    for case in args.cases:
        if case == 'dense_clutter_laser':
            times, names, most = timed_clutter(args.clutter_worlds)
            segments = '0'
        else:
            scenario = floor() if case == 'floor' else WORLDS[case]
            segments = str(sum(isinstance(o, Segment) for o in grid_map(scenario).obstacle_list))
            times, names, most = timed_walk(scenario)
        ms, cpu = (np.array(times) * 1e3).T
        print(f'| {case} | {segments} | {len(ms)} | {np.median(ms):.2f} | {np.percentile(ms, 99):.2f} | '
              f'{ms.max():.2f} | {np.percentile(cpu, 99):.2f} | {len(names)} | {most} |', flush=True)
    print(f'load average at the end: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')


if __name__ == '__main__':
    main()
