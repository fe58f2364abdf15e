"""Benchmark (a): latency of one FAStep step plan (50 fireflies), before and after the fast step fitness, with
the attraction sample, and against a plain-Python-loop FAStep.

    python -m benchmarks.step_latency [--seeds 20] [--sample 5] [--crowd 40] [--no-loop]

Step problems: those FAStep-Kinematic poses in a table2_s2 run, and with --crowd N those of the first 30 s of
benchmarks.scale's crowd of N robots. Each is solved with seeds 0..S-1, the variants interleaved per seed so
they share the machine's load: before (the plain step fitness, fastep_testing/step_reference.py), after
(StepProblem.fitness; waypoints must be identical), sample k (attraction_sample=k), merged (merged_moves) and
loop (fastep_testing/fastep_loop.py, seed 0 only). Wall and CPU time per plan (medians) and the load average.
"""

from __future__ import annotations

import argparse
import os
import time
from typing import Callable

import numpy as np

from benchmarks.common import captured_step_problems, median_ms
from benchmarks.scale import crowd_scenario_data
from fastep_core.optimize import OptimizeResult, fastep
from fastep_core.planning import PlannerParams
from fastep_core.planning.swarm.step import StepProblem
from fastep_core.scenario import parse_scenario
from fastep_testing.fastep_loop import fastep_loop
from fastep_testing.step_reference import ReferenceTerms

Timed = dict[str, list[float]]
VARIANTS = ('before', 'after', 'sample', 'merged')
DEPARTURES = ('sample', 'merged')


def solve(optimizer: Callable[..., OptimizeResult], fun: Callable[[np.ndarray], np.ndarray], problem: StepProblem,
          params: PlannerParams, seed: int, **extra: object) -> OptimizeResult:
    return optimizer(fun, problem.bounds(), n_fireflies=params.n_fireflies, max_iter=params.max_iter,
                     patience=params.patience, gamma=params.gamma, beta0=params.beta0, alpha=params.alpha,
                     alpha_damping=params.alpha_damping, tol=params.tol, rng=np.random.default_rng(seed), **extra)


def timed(wall: Timed, cpu: Timed, name: str, optimizer: Callable[..., OptimizeResult],
          fun: Callable[[np.ndarray], np.ndarray], problem: StepProblem, params: PlannerParams, seed: int,
          **extra: object) -> OptimizeResult:
    w, c = time.perf_counter(), time.process_time()
    result = solve(optimizer, fun, problem, params, seed, **extra)
    wall.setdefault(name, []).append(time.perf_counter() - w)
    cpu.setdefault(name, []).append(time.process_time() - c)
    return result


def bench(title: str, problems: list[StepProblem], params: PlannerParams, seeds: int, sample: int,
          loop: bool) -> None:
    wall: Timed = {}
    cpu: Timed = {}
    nfev: dict[str, list[int]] = {'after': [], 'sample': [], 'merged': []}
    excess: dict[str, list[float]] = {name: [] for name in DEPARTURES}
    same = 0
    load = os.getloadavg()[0]
    n = len(VARIANTS)
    for problem in problems:
        reference = ReferenceTerms(problem)
        for seed in range(seeds):
            results = {}
            for name in VARIANTS[seed % n:] + VARIANTS[:seed % n]:        # each variant first as often
                fun = reference.fitness if name == 'before' else problem.fitness
                extra: dict[str, object] = {'attraction_sample': sample} if name == 'sample' else \
                    {'merged_moves': True} if name == 'merged' else {}
                results[name] = timed(wall, cpu, name, fastep, fun, problem, params, seed, **extra)
            before, after = results['before'], results['after']
            same += int(np.array_equal(before.x, after.x) and before.fun == after.fun)
            for name in nfev:
                nfev[name].append(results[name].nfev)
            if after.fun < 1e6:
                for name in DEPARTURES:
                    excess[name].append(results[name].fun - after.fun)
        if loop:
            timed(wall, cpu, 'loop', fastep_loop, problem.fitness, problem, params, 0)
    load = max(load, os.getloadavg()[0])
    plans = len(problems) * seeds
    print(f'\n{title}: {len(problems)} step problems x {seeds} seeds; fireflies {params.n_fireflies}; '
          f'load average up to {load:.2f}')
    print(f'  before (plain fitness, main):   median {median_ms(wall["before"]):.2f} ms wall, '
          f'{median_ms(cpu["before"]):.2f} ms CPU per plan')
    print(f'  after (fast fitness):           median {median_ms(wall["after"]):.2f} ms wall, '
          f'{median_ms(cpu["after"]):.2f} ms CPU per plan; same waypoint and value in {same}/{plans} plans; '
          f'median evaluations {int(np.median(nfev["after"]))}')
    for name, label in (('sample', f'attraction_sample={sample}:'), ('merged', 'merged_moves:')):
        print(f'  {label:<31} median {median_ms(wall[name]):.2f} ms wall, {median_ms(cpu[name]):.2f} ms CPU per '
              f'plan ({median_ms(cpu[name]) / median_ms(cpu["after"]):.2f} x after\'s); median evaluations '
              f'{int(np.median(nfev[name]))}')
        if excess[name]:
            e = np.asarray(excess[name])
            print(f'    fitness reached minus the paper\'s (same seed): median {np.median(e):+.1e}, '
                  f'90th percentile {np.percentile(e, 90):+.1e}, worst {e.max():+.1e}; worse by more than tol '
                  f'({params.tol:g}) in {np.mean(e > params.tol) * 100:.0f} % of plans, better in '
                  f'{np.mean(e < -params.tol) * 100:.0f} %')
    if loop:
        print(f'  plain-loop fastep:              median {median_ms(wall["loop"]):.1f} ms wall per plan; speed-up '
              f'of after over it (medians, same run) {median_ms(wall["loop"]) / median_ms(wall["after"]):.0f}x')


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='step_latency', description=__doc__.splitlines()[0])
    p.add_argument('--seeds', type=int, default=20, help='seeds per step problem (default 20)')
    p.add_argument('--sample', type=int, default=5, help='k of attraction_sample (default 5)')
    p.add_argument('--crowd', type=int, default=0, metavar='N', help='also a crowd of N robots (e.g. 40)')
    p.add_argument('--crowd-problems', type=int, default=30, metavar='K', help='of which K problems (default 30)')
    p.add_argument('--no-loop', action='store_true', help='skip the plain-loop reference (slow)')
    args = p.parse_args(argv)
    params = PlannerParams()
    bench('table2_s2', captured_step_problems('table2_s2'), params, args.seeds, args.sample, not args.no_loop)
    if args.crowd:
        problems = captured_step_problems(parse_scenario(crowd_scenario_data(args.crowd, 0, 30.0)))
        every = max(1, len(problems) // args.crowd_problems)
        bench(f'crowd of {args.crowd} robots (benchmarks.scale, first 30 s)', problems[::every][:args.crowd_problems],
              params, max(1, args.seeds // 4), args.sample, False)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
