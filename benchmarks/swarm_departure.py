"""Benchmark: FAStep-Kinematic with the paper's swarm against one of its departures, on whole Table 2 runs.

    python -m benchmarks.swarm_departure [--set attraction_sample=5] [--seeds 20]
    python -m benchmarks.swarm_departure --set merged_moves=1

The departures (PlannerParams, fastep_core/optimize/fastep.py) are off by default: `attraction_sample=k`
attracts each firefly to k brighter ones, `merged_moves=1` evaluates an iteration's attraction and stepping-ahead
candidates in one call. On the three Table 2 scenarios, FAStep-Kinematic runs with seeds 0..S-1 once with the
paper's swarm and once with the departure; per scenario: arrivals without collision, path length (mean, and the
paired difference with its two-sided p-value from a t-test over the seeds), swarm activations, the time spent
inside the step optimizer (plan_time, wall, mean per run) and CPU per run (process time, median), and the load
average. The two runs of a seed follow each other, so they share the machine's load.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time

import numpy as np
from scipy import stats

from fastep_core.scenario import load_scenario
from fastep_core.simulator import RobotRun, simulate

SCENARIOS = ('table2_s1', 'table2_s2', 'table2_s3')


def _setting(text: str) -> tuple[str, float]:
    name, sep, value = text.partition('=')
    if not sep:
        raise argparse.ArgumentTypeError(f'expected NAME=VALUE, got {text!r}')
    try:
        return name, float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{name}: {value!r} is not a number') from None


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='swarm_departure', description=__doc__.splitlines()[0])
    p.add_argument('--set', type=_setting, default=('attraction_sample', 5.0), metavar='NAME=VALUE',
                   help='the departure: a planner parameter and its value (default attraction_sample=5)')
    p.add_argument('--seeds', type=int, default=20, help='seeds 0..S-1 (default 20)')
    args = p.parse_args(argv)
    name, value = args.set
    label = f'{name}={value:g}'
    print(f'load average at the start {os.getloadavg()[0]:.2f}')
    print('| scenario | swarm | arrived | path (m) | activations | plan time per run (ms) | CPU per run (ms) |')
    print('|---|---|---|---|---|---|---|')
    for scenario_name in SCENARIOS:
        paper = load_scenario(scenario_name)
        departure = dataclasses.replace(paper, planner=paper.planner.with_overrides({name: value}))
        runs: dict[str, list[RobotRun]] = {'paper': [], label: []}
        cpu: dict[str, list[float]] = {'paper': [], label: []}
        for seed in range(args.seeds):
            for which, scenario in (('paper', paper), (label, departure))[::1 if seed % 2 else -1]:
                start = time.process_time()
                runs[which].append(simulate(scenario, 'fastep', seed).robots[0])
                cpu[which].append(time.process_time() - start)
        for which in runs:
            rs = runs[which]
            arrived = sum(r.reached and not r.collided for r in rs)
            length = np.array([r.path_length for r in rs])
            print(f'| {scenario_name} | {which} | {arrived}/{len(rs)} | {length.mean():.3f} | '
                  f'{np.mean([r.activations for r in rs]):.1f} | {np.mean([r.plan_time for r in rs]) * 1e3:.1f} | '
                  f'{np.median(cpu[which]) * 1e3:.1f} |')
        a = np.array([r.path_length for r in runs['paper']])
        b = np.array([r.path_length for r in runs[label]])
        diff = b - a
        p_value = float(stats.ttest_rel(b, a).pvalue) if np.any(diff != 0.0) else 1.0
        print(f'| {scenario_name} | {label} - paper | | {diff.mean():+.3f} (p = {p_value:.2g}) | | | |')
    print(f'load average at the end {os.getloadavg()[0]:.2f}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
