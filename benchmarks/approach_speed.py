"""min_approach_speed swept over the built-in scenarios and the world families (issue 14, item 7).

    python -m benchmarks.approach_speed [--speeds 0 0.3 0.5] [--worlds 6] [--algorithms fastep aco ...]
    python -m benchmarks.approach_speed --per-scenario     # each built-in scenario, seed 0: 0 -> the default

Per speed and planner: runs that arrived without collision, mean path length and simulated time over those,
the longest simulated time, and mean CPU seconds per run (process time, immune to other load). The built-in
set leaves Table 2's scenarios out (they set min_approach_speed 0 themselves); the families set is the first
WORLDS worlds of every family of the families benchmark (fastep-bench --families). Results: docs/approach_speed.md.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from fastep_core.experiments import batches, families
from fastep_core.experiments.batches import Record
from fastep_core.experiments.random_worlds import FAMILIES
from fastep_core.planning.algorithms import drives
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import builtin_names, load_scenario
from fastep_core.simulator import simulate


def rows(records: list[Record], speed: float, label: str) -> list[str]:
    out = []
    for algorithm in sorted({r.algorithm for r in records}):
        runs = [r for r in records if r.algorithm == algorithm]
        ok = [r for r in runs if r.reached and not r.collided]
        path = np.mean([r.path_length for r in ok]) if ok else np.nan
        sim = [r.sim_time for r in ok if r.sim_time is not None]
        out.append(f'| {label} | {speed:g} | {algorithm} | {len(ok)}/{len(runs)} | {path:.2f} | '
                   f'{np.mean(sim) if sim else np.nan:.1f} | {max(sim, default=np.nan):.1f} | '
                   f'{np.mean([r.cpu_time for r in runs]):.3f} |')
    return out


def per_scenario(algorithms: list[str]) -> None:
    """Each built-in scenario and planner, seed 0: path (summed over robots), mean sim time, activations, CPU
    with min_approach_speed 0 and with the default (Table 2's scenarios set 0: unchanged)."""
    default = PlannerParams().min_approach_speed
    print(f'| scenario | planner | path (m) 0 -> {default:g} | sim time (s) | activations | CPU (s) |')
    print('|---|---|---|---|---|---|')
    for name in builtin_names():
        scenario = load_scenario(name)
        for algorithm in algorithms:
            if not all(drives(algorithm, r.model) for r in scenario.robots):
                continue
            cells = []
            for planner in (scenario.planner.with_overrides({'min_approach_speed': 0.0}), scenario.planner):
                cpu = time.process_time()
                run = simulate(replace(scenario, planner=planner), algorithm, 0)
                cpu = time.process_time() - cpu
                times = [r.sim_time if r.sim_time is not None else np.nan for r in run.robots]
                cells.append((sum(r.path_length for r in run.robots), float(np.mean(times)),
                              sum(r.activations for r in run.robots), cpu,
                              all(r.reached and not r.collided for r in run.robots)))
            (p0, t0, a0, c0, ok0), (p1, t1, a1, c1, ok1) = cells
            note = '' if ok0 and ok1 else f' (arrived without collision: {ok0} -> {ok1})'
            print(f'| {name} | {algorithm}{note} | {p0:.2f} -> {p1:.2f} | {t0:.1f} -> {t1:.1f} | {a0} -> {a1} | '
                  f'{c0:.2f} -> {c1:.2f} |', flush=True)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='approach_speed', description=__doc__.splitlines()[0])
    p.add_argument('--speeds', type=float, nargs='+', default=[0.0, 0.3, 0.5])
    p.add_argument('--worlds', type=int, default=6, help='worlds per family (0: no families)')
    p.add_argument('--algorithms', nargs='+', default=['fastep', 'fastep_paper', 'aco', 'optimal', 'fastep_route'])
    p.add_argument('--workers', type=int, default=2)
    p.add_argument('--per-scenario', action='store_true', help='the per-scenario table instead of the sweep')
    args = p.parse_args(argv)
    if args.per_scenario:
        per_scenario(args.algorithms)
        return 0
    sets = {'built-in': [s for s in builtin_names() if s not in batches.TABLE2]}
    if args.worlds > 0:
        sets['families'] = families.family_sources(list(FAMILIES), args.worlds)
    print('| set | min_approach_speed | planner | arrived | path (m) | sim time (s) | longest (s) | CPU / run (s) |')
    print('|---|---|---|---|---|---|---|---|')
    for label, sources in sets.items():
        for speed in args.speeds:
            wall = time.time()
            records = batches.run_batch(sources, args.algorithms, 1, args.workers,
                                            overrides={'min_approach_speed': speed})
            print('\n'.join(rows(records, speed, label)), flush=True)
            print(f'<!-- {label} at {speed:g}: {time.time() - wall:.0f} s wall, load {families.load_average():.1f} -->',
                  flush=True)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
