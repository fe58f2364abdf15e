"""Benchmark: time of one laser scan (fastep_core/sensing/laser.py) at 360 beams against 50 obstacles and 10 robots.

The world: 35 circles (10 of them moving, placed where they are at the scan's time) and 15 segments scattered
over a 20 m square around the scanner, 10 robots as circles of radius 0.35 m; a 10 m, 360-beam full-turn scanner
with 0.01 m noise. Each repetition scans from a new pose (and evaluates the movers' positions at a new time,
part of what a tick pays). Issue 13's budget is 2 ms per control tick for scanner + perception + tracking.
Prints the median and the 90th percentile of wall and CPU time per scan, and the load average.

Run: `PYTHONPATH=. .venv/bin/python -m benchmarks.laser_scan [--repeats N] [--beams B]`.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from fastep_core.dynamic_world import Motion, Movers
from fastep_core.geometry import Circle
from fastep_core.sensing.laser import LaserSpec, scan


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--repeats', type=int, default=2000)
    parser.add_argument('--beams', type=int, default=360)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    still = rng.uniform(-10, 10, (25, 2)), rng.uniform(0.2, 1.0, 25)
    movers = Movers([Circle((float(x), float(y)), 0.5) for x, y in rng.uniform(-10, 10, (10, 2))],
                    [Motion(tuple((float(x), float(y)) for x, y in rng.uniform(-10, 10, (3, 2))), 0.5)
                     for _ in range(10)])
    starts = rng.uniform(-10, 10, (15, 2))
    ends = starts + rng.uniform(-3, 3, (15, 2))
    robots = rng.uniform(-10, 10, (10, 2))
    spec = LaserSpec(range=10.0, beams=args.beams, noise=0.01)
    noise = np.random.default_rng(1)
    poses = np.column_stack([rng.uniform(-2, 2, (args.repeats, 2)), rng.uniform(-np.pi, np.pi, args.repeats)])
    wall, cpu = [], []
    for k, pose in enumerate(poses):
        w0, c0 = time.perf_counter(), time.process_time()
        centres = np.concatenate([still[0], movers.positions(0.05 * k), robots])
        radii = np.concatenate([still[1], movers.radii, np.full(len(robots), 0.35)])
        result = scan(spec, pose, noise, 0.05 * k, centres, radii, starts, ends)
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    assert len(result.ranges) == args.beams
    w, c = np.array(wall) * 1e3, np.array(cpu) * 1e3
    load = os.getloadavg()
    print(f'{args.beams} beams, {len(still[1]) + len(movers)} circles ({len(movers)} moving) + {len(starts)} '
          f'segments + {len(robots)} robots, {args.repeats} scans')
    print(f'wall: median {np.median(w):.3f} ms, p90 {np.percentile(w, 90):.3f} ms; '
          f'CPU: median {np.median(c):.3f} ms, p90 {np.percentile(c, 90):.3f} ms')
    print(f'load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}')


if __name__ == '__main__':
    main()
