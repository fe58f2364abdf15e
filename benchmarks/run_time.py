"""Benchmark (b): wall time of whole in-process runs and the FAStep/ACO compute-time ratio.

compute_time is wall seconds spent planning and simulating a robot (the paper's "time" in Table 2 is MATLAB
run time, dominated by step generation). Run: `.venv/bin/python -m benchmarks.run_time`.
"""

from __future__ import annotations

import time

import numpy as np

from fastep_core.scenario import load_scenario
from fastep_core.simulator import simulate

SEEDS = range(10)
PAPER_RATIO = {'table2_s1': 69.62 / 133.76, 'table2_s2': 154.04 / 283.25, 'table2_s3': 95.80 / 173.27}


def main() -> None:
    scenario = load_scenario('table2_s2')
    walls = []
    for seed in SEEDS:
        start = time.perf_counter()
        simulate(scenario, 'fastep', seed)
        walls.append(time.perf_counter() - start)
    print(f'table2_s2 whole FAStep-Kinematic run in-process: median {np.median(walls):.3f} s, '
          f'max {max(walls):.3f} s over {len(walls)} seeds')
    for name, paper in PAPER_RATIO.items():
        scenario = load_scenario(name)
        robots = {alg: [simulate(scenario, alg, s).robots[0] for s in SEEDS] for alg in ('fastep', 'aco')}
        f, a = (np.mean([r.compute_time for r in robots[alg]]) for alg in ('fastep', 'aco'))
        pf, pa = (np.mean([r.plan_time for r in robots[alg]]) for alg in ('fastep', 'aco'))
        print(f'{name}: compute time FAStep {f * 1e3:.0f} ms, ACO {a * 1e3:.0f} ms, ratio {f / a:.2f}; '
              f'step planning only FAStep {pf * 1e3:.0f} ms, ACO {pa * 1e3:.0f} ms, ratio {pf / pa:.2f} '
              f'(paper {paper:.2f})')


if __name__ == '__main__':
    main()
