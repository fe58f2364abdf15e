"""fastep-tune: choose the step fitness weights a, b, c and the step radius by optimisation, not by hand.

    fastep-tune [--train ...] [--test ...] [--seeds 2] [--test-seeds 10] [--popsize 5] [--maxiter 3]
                [--workers 2 | --cluster ADDRESS|local:N] [--seed 0] [--out FILE.md] [--json FILE]

Why: the paper sets a, b, c by brute force and names a principled way as future work. Seeded differential evolution
(scipy) minimises J = mean over runs and robots of (path length + PENALTY if it collided or did not arrive), PENALTY
= 1000 m so a setting that fails anywhere loses, over a, b in [0.1, 1], log10 c in [-5, -2] (c spans three decades)
and step_radius in [1, 4] m, the paper's ranges. Table 1's setting is in the initial population, so the result is
never worse on the training runs; every candidate is scored on the same seeds (common random numbers), so J is a
fixed function. The result is checked against Table 1 on held-out scenarios and seeds. Default: train on table2_s2,
table2_s3, case_study_1, seeds 0-1, popsize 5 for 3 generations on 2 workers; held out table2_s1, case_study_2,
application, open_field, seeds 100-109. --cluster scores each generation on Dask (experiments.cluster), same result.
Exit 0 after a search, 2 with one line on stderr for bad input.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import math
import shlex
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.cli import MAX_ITERATIONS, MAX_POPSIZE, MAX_RUNS, MAX_WORKERS, Parser, count, fail, guard, seed
from fastep_core.experiments import batches
from fastep_core.experiments.cluster import CLUSTER_HELP, ClusterSpec, Engine, cluster_spec, open_cluster
from fastep_core.planning.params import PlannerParams

__all__ = ['PARAMETERS', 'PENALTY', 'TRAIN', 'TEST', 'TuningResult', 'cost', 'decode', 'tune', 'evaluate',
           'main']

PROG = 'fastep-tune'

PENALTY = 1000.0
"""Added to a run's path length (m) when the robot collided or did not arrive."""

PARAMETERS: dict[str, tuple[float, float]] = {
    'a': (0.1, 1.0),
    'b': (0.1, 1.0),
    'log10_c': (-5.0, -2.0),
    'step_radius': (1.0, 4.0),
}
"""The search box; c is searched on a log scale."""

TRAIN: tuple[str, ...] = ('table2_s2', 'table2_s3', 'case_study_1')
TEST: tuple[str, ...] = ('table2_s1', 'case_study_2', 'application', 'open_field')


def decode(x: Sequence[float] | NDArray[np.float64]) -> dict[str, float]:
    """A point of the search box as planner parameter overrides."""
    a, b, log10_c, step_radius = (float(v) for v in x)
    return {'a': a, 'b': b, 'c': 10.0 ** log10_c, 'step_radius': step_radius}


def encode(params: PlannerParams) -> np.ndarray:
    return np.array([params.a, params.b, math.log10(params.c), params.step_radius])


def run_cost(records: Sequence[batches.Record]) -> float:
    """Mean of path length + PENALTY per failed robot."""
    return float(np.mean([r.path_length + (0.0 if r.ok else PENALTY) for r in records]))


def cost(x: Sequence[float] | NDArray[np.float64], train: Sequence[str], seeds: Sequence[int],
         algorithm: str = 'fastep') -> float:
    """J(x): every training scenario, every seed, in this process."""
    overrides = tuple(sorted(decode(x).items()))
    records = [r for s in train for seed in seeds
               for r in batches.run_task((s, algorithm, seed), overrides)]
    return run_cost(records)


@dataclass(frozen=True)
class TuningResult:
    """Tuned parameters, their training cost against Table 1's, and the search's size."""

    params: dict[str, float]
    cost: float
    table1_cost: float
    evaluations: int
    generations: int
    seconds: float


def tune(train: Sequence[str] = TRAIN, seeds: Sequence[int] = (0, 1), *, popsize: int = 5, maxiter: int = 3,
         workers: int = 2, seed: int = 0, algorithm: str = 'fastep',
         log: Callable[[str], None] | None = None, cluster: ClusterSpec | Engine | str | None = None) -> TuningResult:
    """Differential evolution over PARAMETERS (Table 1 in the initial population); returns the best found.
    `cluster` (fastep_core.experiments.cluster): each generation's candidates are scored there instead of on `workers`
    processes, the same result."""
    from scipy.optimize import Bounds, differential_evolution
    fun = functools.partial(cost, train=tuple(train), seeds=tuple(seeds), algorithm=algorithm)
    bounds = Bounds(*np.array(list(PARAMETERS.values()), dtype=float).T)
    x0 = encode(PlannerParams())
    started = time.perf_counter()
    generation = [0]

    def callback(intermediate_result: Any) -> None:
        generation[0] += 1
        if log:
            log(f'fastep-tune: generation {generation[0]}/{maxiter}: best J = {intermediate_result.fun:.3f} at '
                + ', '.join(f'{k}={v:.4g}' for k, v in decode(intermediate_result.x).items()))

    kwargs: dict[str, Any] = dict(popsize=popsize, maxiter=maxiter, x0=x0, init='latinhypercube', polish=False,
                                  tol=0.0, atol=0.0, updating='deferred', rng=np.random.default_rng(seed),
                                  callback=callback)
    if cluster is not None:
        with contextlib.ExitStack() as stack:
            engine = cluster if isinstance(cluster, Engine) else stack.enter_context(open_cluster(cluster))
            result = differential_evolution(fun, bounds, workers=functools.partial(engine.map, name=PROG), **kwargs)
    elif workers > 1:
        with batches.pool_context().Pool(workers) as pool:
            result = differential_evolution(fun, bounds, workers=pool.map, **kwargs)
    else:
        result = differential_evolution(fun, bounds, **kwargs)
    table1 = fun(x0)
    return TuningResult(decode(result.x), float(result.fun), float(table1), int(result.nfev), generation[0],
                        time.perf_counter() - started)


def evaluate(scenarios: Sequence[str], overrides: dict[str, float] | None, runs: int, seed0: int,
             workers: int, cluster: ClusterSpec | Engine | str | None = None) -> list[batches.Record]:
    """FAStep-Kinematic runs of the scenarios with planner overrides (None: each scenario's own values)."""
    return batches.run_batch(scenarios, ['fastep'], runs, workers, seed0=seed0, overrides=overrides,
                                 cluster=cluster)


def report(result: TuningResult, test: Sequence[str], baseline: Sequence[batches.Record],
           tuned: Sequence[batches.Record], command: str) -> str:
    t1 = PlannerParams()
    lines = ['## Tuning', '', '```', command, '```', '',
             f'Differential evolution, {result.evaluations} candidate evaluations in {result.generations} '
             f'generations, {result.seconds:.0f} s. Training cost J (mean path + {PENALTY:g} m per failed '
             f'robot): Table 1 {result.table1_cost:.3f}, tuned {result.cost:.3f}.', '',
             '| parameter | Table 1 | tuned | range |', '|---|---|---|---|']
    for name, value in result.params.items():
        rng = PARAMETERS.get(name) or PARAMETERS['log10_c']
        shown = f'[{rng[0]:g}, {rng[1]:g}]' if name != 'c' else '[1e-05, 0.01]'
        lines.append(f'| {name} | {getattr(t1, name):g} | {value:.4g} | {shown} |')
    lines += ['', 'Held-out scenarios (not used in the search), other seeds:', '',
              '| scenario | robot | Table 1 path (m) | tuned path (m) | change | Table 1 arrived | tuned arrived | '
              'Table 1 path / opt. | tuned path / opt. |', '|---|---|---|---|---|---|---|---|---|']
    sb = {(s.scenario, s.robot): s for s in batches.summarise(baseline)}
    st = {(s.scenario, s.robot): s for s in batches.summarise(tuned)}
    for scenario in test:
        optimal = batches.optimal_lengths(scenario)
        for robot, opt in optimal.items():
            b, t = sb[(scenario, robot)], st[(scenario, robot)]
            pb, pt = b.mean['path_length'], t.mean['path_length']
            change = (pt - pb) / pb * 100 if pb and not math.isnan(pb) and not math.isnan(pt) else math.nan

            def arrived(s: batches.Summary) -> str:
                return f'{s.arrived}/{s.runs}' + (f' ({s.collided} collided)' if s.collided else '')
            lines.append(f'| {scenario} | {robot} | {pb:.2f} ± {b.std["path_length"]:.2f} | '
                         f'{pt:.2f} ± {t.std["path_length"]:.2f} | {change:+.2f} % | {arrived(b)} | {arrived(t)} | '
                         f'{pb / opt if opt else math.nan:.3f} | {pt / opt if opt else math.nan:.3f} |')
    jb, jt = run_cost(baseline), run_cost(tuned)
    lines += ['', f'Held-out cost J: Table 1 {jb:.3f}, tuned {jt:.3f}.']
    return '\n'.join(lines) + '\n'


def _parser() -> argparse.ArgumentParser:
    p = Parser(prog=PROG, description='Tune a, b, c and step_radius by differential evolution.')
    p.add_argument('--train', nargs='+', default=list(TRAIN), metavar='SCENARIO', help='training scenarios')
    p.add_argument('--test', nargs='+', default=list(TEST), metavar='SCENARIO', help='held-out scenarios')
    p.add_argument('--seeds', type=count(MAX_RUNS), default=2, help='training seeds 0..N-1 per scenario (default 2)')
    p.add_argument('--test-seeds', type=count(MAX_RUNS), default=10, help='held-out seeds 100..100+N-1 (default 10)')
    p.add_argument('--popsize', type=count(MAX_POPSIZE), default=5, help='DE population = popsize x 4 (default 5)')
    p.add_argument('--maxiter', type=count(MAX_ITERATIONS), default=3, help='DE generations (default 3)')
    engine = p.add_mutually_exclusive_group()
    engine.add_argument('--workers', type=count(MAX_WORKERS), help='worker processes (default 2)')
    engine.add_argument('--cluster', type=cluster_spec, metavar='ADDRESS|local:N', help=CLUSTER_HELP)
    p.add_argument('--seed', type=seed, default=0, help='seed of the search (default 0)')
    p.add_argument('--out', type=Path, metavar='FILE.md', help='also write the Markdown report here')
    p.add_argument('--json', type=Path, metavar='FILE', help='write the tuned parameters as JSON')
    return p


def main(argv: Sequence[str] | None = None) -> int:
    return guard(PROG, lambda: _run(argv))


def _run(argv: Sequence[str] | None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.maxiter < 0:
        parser.error(f'--maxiter must be >= 0, got {args.maxiter}')
    overlap = sorted(set(args.train) & set(args.test))
    if overlap:
        parser.error(f'held-out scenarios must not be training scenarios: {", ".join(overlap)}')
    from fastep_core.scenario import load_scenario
    for name in [*args.train, *args.test]:  # a bad one is a FastepError: one line before the search starts
        load_scenario(name)

    def log(text: str) -> None:
        print(text, file=sys.stderr, flush=True)

    workers = args.workers or 2
    with contextlib.ExitStack() as stack:   # one cluster (if any) for the search and both checks
        cluster: Engine | None = None if args.cluster is None else stack.enter_context(open_cluster(args.cluster))
        result = tune(args.train, tuple(range(args.seeds)), popsize=args.popsize, maxiter=args.maxiter,
                      workers=workers, seed=args.seed, log=log, cluster=cluster)
        log(f'fastep-tune: checking on held-out scenarios {", ".join(args.test)}')
        baseline = evaluate(args.test, None, args.test_seeds, 100, workers, cluster)
        tuned = evaluate(args.test, result.params, args.test_seeds, 100, workers, cluster)
    command = ' '.join([PROG, *map(shlex.quote, sys.argv[1:] if argv is None else argv)])
    text = report(result, args.test, baseline, tuned, command)
    print(text)
    try:
        if args.out is not None:
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(text)
            print(f'wrote {args.out}')
        if args.json is not None:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps(asdict(result), indent=1) + '\n')
            print(f'wrote {args.json}')
    except OSError as exc:
        return fail(PROG, f'cannot write output: {exc}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
