"""Benchmark: FAStep-Kinematic with the paper's attraction against attraction to a sample of k brighter fireflies.

    python -m benchmarks.attraction_sample [--sample 5] [--seeds 20]

`attraction_sample` (PlannerParams, fastep_core/optimize/fastep.py) is a departure from the paper, off by
default. On the three Table 2 scenarios, FAStep-Kinematic runs with seeds 0..S-1 once with the paper's swarm
and once with `attraction_sample=k`; per scenario: arrivals without collision, path length (mean, and the
paired difference with its two-sided p-value from a t-test over the seeds), swarm activations and the time
spent inside the step optimizer (plan_time, wall, mean per run), and the load average.
"""

from __future__ import annotations

import argparse
import dataclasses
import os

import numpy as np
from scipy import stats

from fastep_core.scenario import load_scenario
from fastep_core.simulator import simulate

SCENARIOS = ('table2_s1', 'table2_s2', 'table2_s3')


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='attraction_sample', description=__doc__.splitlines()[0])
    p.add_argument('--sample', type=int, default=5, help='k of attraction_sample (default 5)')
    p.add_argument('--seeds', type=int, default=20, help='seeds 0..S-1 (default 20)')
    args = p.parse_args(argv)
    print(f'load average at the start {os.getloadavg()[0]:.2f}')
    print('| scenario | swarm | arrived | path (m) | activations | plan time per run (ms) |')
    print('|---|---|---|---|---|---|')
    for name in SCENARIOS:
        paper = load_scenario(name)
        sampled = dataclasses.replace(paper, planner=paper.planner.with_overrides({'attraction_sample': args.sample}))
        rows = {}
        for label, scenario in (('paper', paper), (f'sample {args.sample}', sampled)):
            runs = [simulate(scenario, 'fastep', seed).robots[0] for seed in range(args.seeds)]
            rows[label] = runs
            arrived = sum(r.reached and not r.collided for r in runs)
            length = np.array([r.path_length for r in runs])
            print(f'| {name} | {label} | {arrived}/{len(runs)} | {length.mean():.3f} | '
                  f'{np.mean([r.activations for r in runs]):.1f} | {np.mean([r.plan_time for r in runs]) * 1e3:.1f} |')
        a = np.array([r.path_length for r in rows['paper']])
        b = np.array([r.path_length for r in rows[f'sample {args.sample}']])
        diff = b - a
        p_value = float(stats.ttest_rel(b, a).pvalue) if np.any(diff != 0.0) else 1.0
        print(f'| {name} | sample - paper | | {diff.mean():+.3f} (p = {p_value:.2g}) | | |')
    print(f'load average at the end {os.getloadavg()[0]:.2f}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
