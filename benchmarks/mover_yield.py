"""A robot meeting movers, tick by tick: how often yielding (planning/yielding.py) slowed it down, made it wait
or moved it out of the way, the closest it came to a mover (against the truth), and the figure of it.

Run: `PYTHONPATH=. .venv/bin/python -m benchmarks.mover_yield [SCENARIO] [--algorithm A] [--seed S]
[--robot NAME] [--out FIGURE.png]` (default: the built-in crossing_movers with fastep, seed 0, its first robot,
docs/figures/yield_crossing.png). `--mover-horizon 0` runs the same without yielding, for comparison.
"""

from __future__ import annotations

import argparse
from collections import Counter
from dataclasses import replace

import numpy as np

from fastep_core.dynamic_world import DynamicWorld
from fastep_core.experiments import cached_scenario
from fastep_core.simulator import Tick, simulate
from msg_tools.plots import save, title, yield_figure


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenario', nargs='?', default='crossing_movers')
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
    yielded = [row[0] for row, kind in zip(rows, kinds) if kind]
    if yielded and rows:
        first, last = yielded[0], yielded[-1]
        snapshots = list(np.linspace(max(0.0, first - 4.0), min(rows[-1][0], last + 4.0), 5))
    else:
        snapshots = list(np.linspace(0.0, rows[-1][0] if rows else 0.0, 5))
    text = title(f'{scenario.name} {robot}', args.algorithm, args.seed)
    print(f'wrote {save(yield_figure(scenario, args.seed, rows, kinds, text, snapshots), args.out)}')


if __name__ == '__main__':
    main()
