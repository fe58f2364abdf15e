"""Benchmark: scanner + perception + tracking per control tick (fastep_core/perception) at 360 beams.

The world of benchmarks/laser_scan.py: 35 circles (10 of them moving on random polylines at 0.5 m/s) and 15
segments over a 20 m square, 10 other robots as circles of radius 0.35 m. The map the robot was given holds
the still circles and the segments, each misplaced by 0.3 m per axis (Gaussian, seeded); half of the still
circles are left off it (unknown). The robot drives a 6 m circle at 1 m/s through that world, one tick every
0.05 s (the simulator's dt); each tick is what the simulator pays for a robot with a sensor: the scan of the
truth (laser.py, with the movers where they are at the tick's time) and Perception.update (points, see-through,
fusion, clustering, circle and wall fits, the Kalman tracker, the belief). Issue 13's budget: 2 ms per tick.
Prints the median and 90th percentile of wall and CPU time per tick, what the robot believed at the end, and
the load average.

Run: `PYTHONPATH=. .venv/bin/python -m benchmarks.perception_latency [--ticks N] [--beams B]`.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from fastep_core.dynamic_world import Motion, Movers
from fastep_core.geometry import Circle, Segment
from fastep_core.perception.belief import Perception
from fastep_core.planning.others import OtherRobot
from fastep_core.sensing.laser import LaserSpec, scan
from fastep_core.world import World


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--ticks', type=int, default=2000)
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
    robot_radii = np.full(len(robots), 0.35)
    others = [OtherRobot(f'r{k}', (float(x), float(y)), (0.0, 0.0), 0.35) for k, (x, y) in enumerate(robots)]
    error = rng.normal(0.0, 0.3, (40, 4))
    known = [Circle((float(c[0] + e[0]), float(c[1] + e[1])), float(r))
             for c, r, e in zip(*still, error) if rng.random() < 0.5]
    known += [Segment((float(a[0] + e[0]), float(a[1] + e[1])), (float(b[0] + e[2]), float(b[1] + e[3])))
              for a, b, e in zip(starts, ends, error[25:])]
    spec = LaserSpec(range=10.0, beams=args.beams, noise=0.01)
    perception = Perception(spec, World((-15.0, -15.0, 15.0, 15.0), tuple(known)))
    noise = np.random.default_rng(1)
    dt, speed, radius = 0.05, 1.0, 6.0
    wall, cpu = [], []
    for k in range(args.ticks):
        t = k * dt
        angle = speed * t / radius
        pose = (radius * math.cos(angle), radius * math.sin(angle), angle + math.pi / 2)
        w0, c0 = time.perf_counter(), time.process_time()
        centres = np.concatenate([still[0], movers.positions(t), robots])
        radii = np.concatenate([still[1], movers.radii, robot_radii])
        reading = scan(spec, pose, noise, t, centres, radii, starts, ends)
        belief = perception.update(t, pose, reading, others)
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    w, c = np.array(wall) * 1e3, np.array(cpu) * 1e3
    load = os.getloadavg()
    print(f'{args.beams} beams, {len(still[1]) + len(movers)} circles ({len(movers)} moving) + {len(starts)} '
          f'segments + {len(robots)} robots; map: {len(known)} misplaced obstacles; {args.ticks} ticks')
    print(f'per tick (scan + perception + tracking): wall median {np.median(w):.3f} ms, p90 '
          f'{np.percentile(w, 90):.3f} ms; CPU median {np.median(c):.3f} ms, p90 {np.percentile(c, 90):.3f} ms')
    print(f'belief at the end: {len(belief.map_obstacles)} map obstacles kept, {len(belief.dropped)} seen through, '
          f'{len(belief.seen_obstacles)} seen ({sum(isinstance(o, Circle) for o in belief.seen_obstacles)} circles), '
          f'{len(belief.movers)} tracked movers')
    print(f'load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}')


if __name__ == '__main__':
    main()
