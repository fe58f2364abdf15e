"""Benchmark (c): path length against the straight-line distance on each Table 2 scenario.

Run: `.venv/bin/python -m benchmarks.path_length`.
"""

from __future__ import annotations

import math

import numpy as np

from fastep_core.scenario import load_scenario
from fastep_core.simulator import simulate

SEEDS = range(10)
PAPER = {'table2_s1': (56.56, 56.77), 'table2_s2': (59.69, 65.75), 'table2_s3': (45.73, 48.54)}


def main() -> None:
    print('| scenario | straight line | FAStep-Kinematic path (mean +- sd) | ratio | ACO-Kinematic path | ratio '
          '| paper FAStep / ACO | arrived |')
    print('|---|---|---|---|---|---|---|---|')
    for name, (paper_f, paper_a) in PAPER.items():
        scenario = load_scenario(name)
        spec = scenario.robots[0]
        line = math.hypot(spec.goal[0] - spec.start[0], spec.goal[1] - spec.start[1])
        cells, arrived = [], 0
        for alg in ('fastep', 'aco'):
            robots = [simulate(scenario, alg, s).robots[0] for s in SEEDS]
            arrived += sum(r.reached and not r.collided for r in robots)
            lengths = np.array([r.path_length for r in robots])
            cells += [f'{lengths.mean():.2f} +- {lengths.std(ddof=1):.2f}', f'{lengths.mean() / line:.3f}']
        print(f'| {name} | {line:.2f} | {" | ".join(cells)} | {paper_f} / {paper_a} | {arrived}/{2 * len(SEEDS)} |')


if __name__ == '__main__':
    main()
