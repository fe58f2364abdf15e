"""Benchmark: the planner node driving a simulated base on wall time, as on a robot, over the harness's worlds.

Each world (fastep_testing/robot_worlds.py) is one run of fastep_testing.robot_harness.run_world: the base
integrates cmd_vel at 100 Hz, publishes odometry at 50 Hz, a 720-beam 270-degree laser at 20 Hz and a latched
/map; the planner runs as `fastep-planner` with obstacle_source map. One row per run: arrival, collision and
clearance against the true world, time to goal, cmd_vel gaps (over 0.15 s, over 2 control periods, the
longest), the largest |dv/dt| and |domega/dt| between successive commands at the base and over 5 of them
(`dv/dt 5`: jitter-robust), the planner's control_ms p99 and max (its status), its CPU share, and its
phantoms (every world is still: each track it called a mover, the most at once, and the most still obstacles it
believed from its scans where the truth has none).
Targets (issue 30): gaps <= 2 control periods, control p99 <= 5 ms and max <= 25 ms, accelerations <= 2.5 m/s^2
(max_acceleration), planner CPU <= 15 % of a core with the laser, arrival and no collision everywhere; and
(issue 31) no phantom, with the laser at the centre and off it (`--laser-mount 0.25 0 0`).

Run: `.venv/bin/python -m benchmarks.robot_harness [--worlds open_room ...] [--no-laser | --both] [--json out]`.
"""

from __future__ import annotations

import argparse
import json
import os
from dataclasses import asdict
from pathlib import Path

from fastep_testing.robot_harness import HarnessResult, run_world
from fastep_testing.robot_worlds import WORLDS

COLUMNS = ('world', 'laser', 'arrived', 'collided', 'min clr m', 'to goal s', 'gaps>0.15', 'gaps>2T', 'longest s',
           'max dv/dt', 'max dw/dt', 'dv/dt 5', 'dw/dt 5', 'ctl p99 ms', 'ctl max ms', 'planner CPU %',
           'phantom movers', 'most at once', 'phantom obstacles')


def row(r: HarnessResult) -> list[str]:
    def f(value: float, digits: int = 2) -> str:
        return f'{value:.{digits}f}'
    return [r.world, 'on' if r.laser else 'off', 'yes' if r.arrived else f'**no** ({r.status})',
            '**yes**' if r.collided else 'no', f(r.min_clearance), f(r.time_to_goal, 1), str(r.gaps_over_015),
            str(r.gaps_over_2_periods), f(r.longest_gap, 3), f(r.max_dv_dt, 1), f(r.max_domega_dt, 1),
            f(r.mean_dv_dt, 1), f(r.mean_domega_dt, 1), f(r.control_p99_ms, 1), f(r.control_max_ms, 1),
            f(r.planner_cpu, 1), str(r.phantom_movers), str(r.most_movers), str(r.phantom_obstacles)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--worlds', nargs='+', choices=sorted(WORLDS), default=list(WORLDS))
    lasers = parser.add_mutually_exclusive_group()
    lasers.add_argument('--no-laser', action='store_true', help='runs without the laser')
    lasers.add_argument('--both', action='store_true', help='each world with and without the laser')
    parser.add_argument('--timeout', type=float, default=120.0, help='seconds from the goal to give up')
    parser.add_argument('--algorithm', default='', help='the planner\'s algorithm (default: its own)')
    parser.add_argument('--log-dir', type=Path, help='keep each run\'s logs and base record in a folder here')
    parser.add_argument('--json', type=Path, help='write every result here')
    parser.add_argument('--laser-mount', type=float, nargs=3, default=(0.0, 0.0, 0.0), metavar=('X', 'Y', 'YAW'),
                        help='where the laser sits on the base (m, m, rad), the planner told so')
    args = parser.parse_args()
    modes = [True, False] if args.both else [not args.no_laser]
    print(f'load average at the start: {" ".join(f"{v:.2f}" for v in os.getloadavg())}', flush=True)
    print('| ' + ' | '.join(COLUMNS) + ' |')
    print('|' + '---|' * len(COLUMNS), flush=True)
    results = []
    for name in args.worlds:
        for laser in modes:
            log_dir = None if args.log_dir is None else args.log_dir / f'{name}_{"laser" if laser else "nolaser"}'
            result = run_world(name, laser=laser, timeout=args.timeout, algorithm=args.algorithm, log_dir=log_dir,
                              laser_mount=tuple(args.laser_mount))
            results.append(result)
            print('| ' + ' | '.join(row(result)) + ' |', flush=True)
            for note in result.notes:
                print(f'  {name}: {note}', flush=True)
    print(f'load average at the end: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')
    if args.json:
        args.json.write_text(json.dumps([asdict(r) for r in results], indent=1) + '\n')


if __name__ == '__main__':
    main()
