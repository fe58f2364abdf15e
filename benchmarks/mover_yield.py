"""A robot meeting movers, tick by tick: how often yielding (planning/safety/yielding.py) slowed it down, made it wait
or moved it out of the way, the closest it came to a mover (against the truth), and the figure of it.

Run: `PYTHONPATH=. .venv/bin/python -m benchmarks.mover_yield [SCENARIO] [--algorithm A] [--seed S]
[--robot NAME] [--out FIGURE.png]` (default: world 1000019 of the crossing_movers family, where FAStep-Kinematic
touched a mover without yielding, with fastep, seed 0, its first robot, docs/figures/yield_crossing.png).
`--mover-horizon 0` runs the same without yielding, for comparison.
"""

from __future__ import annotations

import argparse
from collections import Counter
from dataclasses import replace

import numpy as np

from fastep_core.dynamic_world import DynamicWorld
from fastep_core.experiments.batches import cached_scenario
from fastep_core.simulator import Tick, simulate
from msg_tools.plots import save, title, yield_figure

PAD = 5.0   # seconds drawn before and after the yielding episode


def episode(times: list[float], kinds: list[str], gap: float = 2.0) -> tuple[float, float]:
    """The longest stretch of ticks where yielding changed the command (changes less than `gap` s apart join
    one stretch), padded by PAD; the whole run when yielding never changed anything."""
    if not times:
        return 0.0, 0.0
    changed = [t for t, kind in zip(times, kinds) if kind]
    if not changed:
        return times[0], times[-1]
    best, start, last = (changed[0], changed[0]), changed[0], changed[0]
    for t in changed[1:] + [float('inf')]:
        if t - last > gap:
            if last - start > best[1] - best[0]:
                best = (start, last)
            start = t
        last = t
    return max(times[0], best[0] - PAD), min(times[-1], best[1] + PAD)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenario', nargs='?', default='crossing_movers:1000019')
    parser.add_argument('--algorithm', default='fastep')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--robot', default=None, help='robot to follow (default: the first)')
    parser.add_argument('--mover-horizon', type=float, default=None, help='override the planner parameter')
    parser.add_argument('--out', default='docs/figures/yield_crossing.png')
    args = parser.parse_args(argv)
    scenario = cached_scenario(args.scenario)
    if args.mover_horizon is not None:
        scenario = replace(scenario, planner=scenario.planner.with_overrides({'mover_horizon': args.mover_horizon}))
    robot = args.robot or scenario.robots[0].name
    spec = next(s for s in scenario.robots if s.name == robot)
    truth = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs)
    rows: list[tuple[float, float, float, float]] = []
    kinds: list[str] = []
    gaps: list[float] = []

    def observe(tick: Tick) -> None:
        if tick.name != robot:
            return
        rows.append((tick.t, float(tick.state[0]), float(tick.state[1]), float(np.hypot(*tick.velocity[:2]))))
        kinds.append(tick.navigator.yield_kind)
        if len(truth.movers):
            centres = truth.movers.positions(np.array([tick.t]))[0]
            gaps.append(float((np.hypot(*(centres - tick.state[:2]).T) - truth.movers.radii - spec.radius).min()))

    run = simulate(scenario, args.algorithm, args.seed, observer=observe)
    result = next(r for r in run.robots if r.name == robot)
    counts = Counter(kinds)
    print(f'{args.scenario} {args.algorithm} seed {args.seed} {robot}: {result.status}; '
          f'{"reached" if result.reached else "NOT reached"}, collided {result.collided}, '
          f'time {result.sim_time}, min clearance {result.min_clearance:.3f} m')
    print('ticks: ' + ', '.join(f'{k or "as planned"} {n}' for k, n in sorted(counts.items())))
    if gaps:
        print(f'closest to a mover (surface to surface): {min(gaps):.3f} m')
    window = episode([row[0] for row in rows], kinds)
    snapshots = list(np.linspace(window[0], window[1], 5))
    print(f'figure: {window[0]:.1f}-{window[1]:.1f} s, the longest run of ticks yielding changed (+-{PAD:g} s)')
    text = title(f'{scenario.name} {robot}', args.algorithm, args.seed)
    print(f'wrote {save(yield_figure(scenario, args.seed, rows, kinds, text, snapshots, window), args.out)}')


if __name__ == '__main__':
    main()
