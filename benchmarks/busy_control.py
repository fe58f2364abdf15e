"""Benchmark: a robot on wall time beside busy processes: the late control loop slows it, it meets nothing.

    python -m benchmarks.busy_control [--busy 0 8 16] [--worlds wall_ahead unmapped_box] [--json OUT]

Each run is fastep_testing.robot_harness.run_world (the planner node and a simulated base as separate processes
on wall time, a 720-beam laser) with `--busy` processes spinning on the CPU beside them (the 2-core machine's
load rises by that many). One row per run: arrival, collision and least clearance against the true world, the
longest gap between commands at the base, the most lateness the planner's status gave (`late`: its worst recent
tick gap, odometry and scan age beyond what is due; fastep_core/planning/safety/lateness.py), how many statuses said the
speed was reduced for it, and the time to the goal. Targets: no collision in any row; lateness seen and the
speed reduced where commands came late.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
from dataclasses import asdict
from typing import Sequence

from fastep_testing.robot_harness import HarnessResult, run_world

COLUMNS = ('world', 'busy', 'load', 'arrived', 'collided', 'min clr m', 'longest gap s', 'most late s',
           'slowed statuses', 'to goal s')


def spinners(count: int) -> list[subprocess.Popen[bytes]]:
    """`count` processes that keep a core busy each until stopped."""
    return [subprocess.Popen([sys.executable, '-c', 'while True: pass'], stdin=subprocess.DEVNULL)
            for _ in range(count)]


def stop(processes: Sequence[subprocess.Popen[bytes]]) -> None:
    for process in processes:
        process.kill()
    for process in processes:
        process.wait()


def row(r: HarnessResult, busy: int) -> list[str]:
    return [r.world, str(busy), f'{r.load[0]:.1f}', 'yes' if r.arrived else f'**no** ({r.status})',
            '**yes**' if r.collided else 'no', f'{r.min_clearance:.2f}', f'{r.longest_gap:.3f}',
            f'{r.most_late:.2f}', str(r.slowed), 'n/a' if math.isnan(r.time_to_goal) else f'{r.time_to_goal:.1f}']


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='busy_control', description=__doc__.splitlines()[0])
    parser.add_argument('--busy', type=int, nargs='+', default=[0, 8, 16], help='busy processes beside each run')
    parser.add_argument('--worlds', nargs='+', default=['wall_ahead', 'unmapped_box'])
    parser.add_argument('--timeout', type=float, default=180.0, help='s a run may take once its goal is sent')
    parser.add_argument('--json', help='write every run as JSON here')
    args = parser.parse_args(argv)
    rows, runs = [], []
    for busy in args.busy:
        for world in args.worlds:
            processes = spinners(busy)
            try:
                result = run_world(world, timeout=args.timeout, start_timeout=120.0)
            finally:
                stop(processes)
            rows.append(row(result, busy))
            runs.append({'busy': busy, **asdict(result)})
            print(' | '.join(rows[-1]), flush=True)
    print(f'\n| {" | ".join(COLUMNS)} |\n|{"---|" * len(COLUMNS)}')
    for line in rows:
        print(f'| {" | ".join(line)} |')
    print(f'\n{os.cpu_count()} cores')
    if args.json:
        with open(args.json, 'w') as out:
            json.dump(runs, out, indent=1)
    return 1 if any(r['collided'] for r in runs) else 0


if __name__ == '__main__':
    sys.exit(main())
