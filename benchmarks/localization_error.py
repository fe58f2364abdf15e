"""Perception with a localization off the truth: the families whose robots have a laser, each robot's pose off by a
constant offset and a drift (fastep_core.perception.uncertainty.PoseError, simulate's pose_error), its perception
told nothing (as before issue 43) or told the uncertainty; and with no error at all, for reference.

    python -m benchmarks.localization_error [--families dense_clutter ...] [--worlds 5] [--algorithms fastep_route]
        [--offset 0.03 -0.02 1.0] [--drift 0.002 0.02] [--json FILE]

Offset in metres and degrees, drift in m/m and degrees/m. Told: a tolerance of the offset's size (0.04 m, 1.2 times
its yaw) plus the drift's bound for the distance driven. Per family and case: robot runs, arrivals, collisions,
failures 'no valid path', other failures, and obstacles perception added within 0.3 m of a mapped one (walls
seen beside the map's) at the end, summed. Lock step: deterministic.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import defaultdict

import numpy as np

from fastep_core.experiments.batches import cached_scenario
from fastep_core.experiments.random_worlds import FAMILY_SEED0, family_source
from fastep_core.geometry import Circle, Obstacles
from fastep_core.perception.uncertainty import OdometryDrift, PoseError, PoseUncertainty
from fastep_core.simulator import simulate

FAMILIES = ('dense_clutter', 'dense_clutter_laser', 'unknown_obstacles', 'misplaced_obstacles', 'crossing_movers',
            'dynamic_mix')
CASES = ('no error', 'told nothing', 'told')
BESIDE = 0.3   # m: a seen obstacle this near a mapped one is counted as one beside it


def beside_the_map(belief: object) -> int:
    """Obstacles perception added within BESIDE of an obstacle of the map it started from."""
    world = getattr(belief, 'world', None)
    seen, mapped = getattr(world, 'seen_obstacles', ()), getattr(world, 'map_obstacles', ())
    if not seen or not mapped:
        return 0
    on_map = Obstacles(mapped)
    count = 0
    for item in seen:
        ends = [item.center] if isinstance(item, Circle) else [item.start, item.end]
        if float(on_map.clearance(np.array(ends, dtype=float)).min()) < BESIDE + (
                item.radius if isinstance(item, Circle) else 0.0):
            count += 1
    return count


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--families', nargs='+', default=list(FAMILIES))
    parser.add_argument('--worlds', type=int, default=5)
    parser.add_argument('--algorithms', nargs='+', default=['fastep_route'])
    parser.add_argument('--offset', nargs=3, type=float, default=[0.03, -0.02, 1.0], metavar=('DX', 'DY', 'DEG'))
    parser.add_argument('--drift', nargs=2, type=float, default=[0.002, 0.02], metavar=('M_PER_M', 'DEG_PER_M'))
    parser.add_argument('--json', default=None)
    args = parser.parse_args(argv)
    offset = (args.offset[0], args.offset[1], math.radians(args.offset[2]))
    drift = OdometryDrift(args.drift[0], math.radians(args.drift[1]))
    tolerance = PoseUncertainty(math.hypot(offset[0], offset[1]) + 0.004, 1.2 * abs(offset[2]))
    totals: dict[tuple[str, str, str], dict[str, int]] = defaultdict(lambda: defaultdict(int))
    failures: list[str] = []
    started = time.time()
    for family in args.families:
        for k in range(args.worlds):
            source = family_source(family, FAMILY_SEED0 + k)
            scenario = cached_scenario(source)
            for algorithm in args.algorithms:
                for case in CASES:
                    error = None if case == 'no error' else PoseError(
                        offset, drift, k, told=tolerance if case == 'told' else None,
                        told_drift=drift if case == 'told' else None)
                    run = simulate(scenario, algorithm, 0, pose_error=error)
                    row = totals[(family, algorithm, case)]
                    for robot in run.robots:
                        row['runs'] += 1
                        row['arrived'] += robot.reached
                        row['collided'] += robot.collided
                        no_path = robot.status.startswith('failed: no valid path')
                        row['no valid path'] += no_path
                        row['other failures'] += not robot.reached and not no_path
                        row['beside the map'] += beside_the_map(robot.belief)
                        if not robot.reached:
                            failures.append(f'{source} {algorithm} {case} {robot.name}: {robot.status[:240]}')
                print(f'{source} {algorithm} done ({time.time() - started:.0f} s)', file=sys.stderr, flush=True)
    columns = ('runs', 'arrived', 'collided', 'no valid path', 'other failures', 'beside the map')
    print('| family | planner | case | ' + ' | '.join(columns) + ' |')
    print('|---|---|---|' + '---|' * len(columns))
    for (family, algorithm, case), row in totals.items():
        print(f'| {family} | {algorithm} | {case} | ' + ' | '.join(str(row[c]) for c in columns) + ' |')
    for line in failures:
        print(f'- {line}')
    if args.json:
        with open(args.json, 'w', encoding='utf-8') as out:
            json.dump({'rows': [{'family': f, 'algorithm': a, 'case': c, **row} for (f, a, c), row in totals.items()],
                       'failures': failures, 'wall_time': time.time() - started}, out, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
