"""Bases that do not do what they are told: the bases-by-goals matrix (fastep_testing/base_matrix.py) in fastep-sim,
and with --harness the same bases on wall time (the robot harness: a wall-time base node, the planner node on its
planning thread, over DDS), in one run.

    python -m benchmarks.closed_loop [--harness] [--algorithm fastep_route] [--json FILE]

Each row: arrived, least clearance to the true walls, how far the goal was driven past, the metres driven after
first reaching it (a loop is more than 1 m), the heading error of a goal with a heading and the base's true speed
when it was said arrived. docs/benchmarks.md ("Bases that do not do as told") has the numbers with the load.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

from fastep_testing.base_matrix import BASES, GOALS, run_base

HARNESS_WORLDS = ('wall_ahead', 'open_room')


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return 'nan' if math.isnan(value) else f'{value:.3f}'
    return str(value)


def _table(rows: list[dict[str, Any]], columns: tuple[str, ...]) -> str:
    lines = ['| ' + ' | '.join(columns) + ' |', '|' + '---|' * len(columns)]
    lines += ['| ' + ' | '.join(_cell(row.get(c, '')) for c in columns) + ' |' for row in rows]
    return '\n'.join(lines)


def simulated(algorithm: str) -> list[dict[str, Any]]:
    rows = []
    for goal in GOALS:
        for base in BASES:
            began = time.perf_counter()
            run = run_base(base, goal, algorithm)
            rows.append({**run.row(), 'wall_s': round(time.perf_counter() - began, 2)})
            print(f'{goal:12s} {base:20s} ok={run.ok}', file=sys.stderr, flush=True)
    return rows


def harness(algorithm: str) -> list[dict[str, Any]]:
    from fastep_testing.robot_harness import run_world

    rows = []
    for world in HARNESS_WORLDS:
        for base in BASES:
            result = run_world(world, algorithm=algorithm, dynamics='' if base == 'kinematic' else base)
            rows.append({'base': base, 'goal': world, 'arrived': result.arrived, 'time': result.time_to_goal,
                         'min_clearance': result.min_clearance, 'final_distance': result.final_distance,
                         'arrival_speed': result.arrival_speed, 'longest_gap': result.longest_gap,
                         'load': round(result.load[0], 1), 'reason': result.reason[:60], 'notes': result.notes})
            print(f'{world:12s} {base:20s} arrived={result.arrived}', file=sys.stderr, flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='python -m benchmarks.closed_loop', description=__doc__.splitlines()[0])
    p.add_argument('--harness', action='store_true', help='also on wall time, in the robot harness (minutes)')
    p.add_argument('--algorithm', default='fastep_route')
    p.add_argument('--json', type=Path, help='write the rows here')
    args = p.parse_args(argv)
    load = os.getloadavg()
    out: dict[str, Any] = {'load_at_start': load, 'simulated': simulated(args.algorithm)}
    print(f'load at the start {load[0]:.1f}\n')
    print(_table(out['simulated'], ('goal', 'base', 'arrived', 'time', 'min_clearance', 'final_distance', 'overshoot',
                                    'after_reaching', 'heading_error', 'arrival_speed', 'ok')))
    if args.harness:
        out['harness'] = harness(args.algorithm)
        print()
        print(_table(out['harness'], ('goal', 'base', 'arrived', 'time', 'min_clearance', 'final_distance',
                                      'arrival_speed', 'longest_gap', 'load')))
    if args.json:
        args.json.write_text(json.dumps(out, indent=1, default=str) + '\n')
    return 0 if all(row['ok'] for row in out['simulated']) else 1


if __name__ == '__main__':
    sys.exit(main())
