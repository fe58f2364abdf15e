"""Benchmark (a): latency of one FAStep step plan (50 fireflies) against a plain-Python-loop FAStep.

Both optimizers make the same moves with the same draws on the same step problems: the ones FAStep-Kinematic
poses in a table2_s2 run. Run: `.venv/bin/python -m benchmarks.step_latency`.
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks.common import captured_step_problems, median_ms
from fastep_core.optimize import fastep
from fastep_core.planning import PlannerParams
from fastep_testing.fastep_loop import fastep_loop


def solve(optimizer, problem, params: PlannerParams, seed: int):
    return optimizer(problem.fitness, problem.bounds(), n_fireflies=params.n_fireflies, max_iter=params.max_iter,
                     patience=params.patience, gamma=params.gamma, beta0=params.beta0, alpha=params.alpha,
                     alpha_damping=params.alpha_damping, tol=params.tol, rng=np.random.default_rng(seed))


def main() -> None:
    params = PlannerParams()
    problems = captured_step_problems('table2_s2')
    fast, slow, same = [], [], 0
    for problem in problems:
        for seed in range(20):
            start = time.perf_counter()
            solve(fastep, problem, params, seed)
            fast.append(time.perf_counter() - start)
        start = time.perf_counter()
        reference = solve(fastep_loop, problem, params, 0)
        slow.append(time.perf_counter() - start)
        same += int(np.allclose(reference.x, solve(fastep, problem, params, 0).x))
    nfev = [solve(fastep, p, params, 0).nfev for p in problems]
    print(f'step problems from a table2_s2 run: {len(problems)}; fireflies {params.n_fireflies}; '
          f'median evaluations per plan {int(np.median(nfev))}')
    print(f'vectorised fastep: median {median_ms(fast):.2f} ms per step plan ({len(fast)} plans)')
    print(f'plain-loop fastep: median {median_ms(slow):.1f} ms per step plan ({len(slow)} plans)')
    print(f'speed-up (medians, same run): {median_ms(slow) / median_ms(fast):.0f}x; '
          f'same waypoint in {same}/{len(problems)} problems')


if __name__ == '__main__':
    main()
