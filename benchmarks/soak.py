"""Soak: run hundreds of random solvable scenarios and count arrivals, collisions and trap escapes.

    python -m benchmarks.soak --scenarios 500 --workers 2 --out out/soak

Each scenario comes from `fastep_core.experiments.random_worlds` (seed i for scenario i), so a failure is reproduced by
`python -m fastep_core.experiments.random_worlds I > s.yaml && fastep-sim s.yaml --seed I`. The scenarios of every
robot that did not arrive, or collided, are written to OUT/failures/ as YAML. A summary (JSON) goes to
OUT/soak.json and a short table to stdout.
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import yaml

from fastep_core.cli import progress_bar
from fastep_core.experiments.random_worlds import random_scenario_data
from fastep_core.planning.algorithms import ALGORITHMS
from fastep_core.scenario import parse_scenario
from fastep_core.simulator import simulate


def run_one(job: tuple[int, str, float | None]) -> dict[str, Any]:
    """Simulate random scenario `seed` with one algorithm; the outcome of each robot."""
    seed, algorithm, trap_timeout = job
    data = random_scenario_data(seed)
    if trap_timeout is not None:
        data = {**data, 'planner': {'trap_timeout': trap_timeout}}
    scenario = parse_scenario(data)
    start = time.perf_counter()
    run = simulate(scenario, algorithm, seed)
    return {
        'seed': seed, 'wall': time.perf_counter() - start, 'data': data,
        'robots': [{'name': r.name, 'model': r.model, 'reached': r.reached, 'collided': r.collided,
                    'escapes': r.escapes, 'manoeuvres': r.manoeuvres, 'status': r.status, 'sim_time': r.sim_time,
                    'min_clearance': r.min_clearance} for r in run.robots],
    }


def summarise(results: list[dict[str, Any]]) -> dict[str, Any]:
    robots = [r for res in results for r in res['robots']]
    failures = [res['seed'] for res in results if any(not r['reached'] or r['collided'] for r in res['robots'])]
    return {
        'scenarios': len(results),
        'robots': len(robots),
        'tractor_trailers': sum(r['model'] == 'tractor_trailer' for r in robots),
        'robots_per_scenario': dict(sorted(Counter(len(res['robots']) for res in results).items())),
        'arrived': sum(r['reached'] for r in robots),
        'collided': sum(r['collided'] for r in robots),
        'robots_that_escaped': sum(r['escapes'] > 0 for r in robots),
        'escapes': sum(r['escapes'] for r in robots),
        'robots_that_manoeuvred': sum(r.get('manoeuvres', 0) > 0 for r in robots),
        'min_clearance': min(r['min_clearance'] for r in robots),
        'failed_scenarios': failures,
        'statuses_of_failures': dict(Counter(r['status'] for r in robots if not r['reached'])),
        'wall_seconds_per_scenario': sum(res['wall'] for res in results) / max(1, len(results)),
    }


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--scenarios', type=int, default=500)
    p.add_argument('--first', type=int, default=0, help='seed of the first scenario')
    p.add_argument('--algorithm', default='fastep', choices=ALGORITHMS)
    p.add_argument('--trap-timeout', type=float, default=None,
                   help='override planner trap_timeout (0 disables trap escape)')
    p.add_argument('--workers', type=int, default=2)
    p.add_argument('--out', type=Path, default=Path('out/soak'))
    p.add_argument('--progress', action='store_true',
                   help='show the progress bar on stderr even when it is not a terminal (e.g. a log file)')
    args = p.parse_args()
    jobs = [(seed, args.algorithm, args.trap_timeout) for seed in range(args.first, args.first + args.scenarios)]
    start = time.perf_counter()
    results = []
    failed_so_far = 0
    # A soak takes most of an hour on two cores: show it is moving, and whether anything failed yet.
    with ProcessPoolExecutor(args.workers) as pool, \
            progress_bar(len(jobs), 'soak', True if args.progress else None, unit='scenario') as bar:
        for result in pool.map(run_one, jobs, chunksize=4):
            results.append(result)
            failed_so_far += any(not r['reached'] or r['collided'] for r in result['robots'])
            bar.set_postfix(failed=failed_so_far, refresh=False)
            bar.update()
    summary = summarise(results)
    summary.update(algorithm=args.algorithm, first_seed=args.first, trap_timeout=args.trap_timeout,
                   wall_seconds=round(time.perf_counter() - start, 1))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / 'soak.json').write_text(json.dumps(summary, indent=2) + '\n')
    failed = [res for res in results if res['seed'] in set(summary['failed_scenarios'])]
    if failed:
        (args.out / 'failures').mkdir(exist_ok=True)
        for res in failed:
            (args.out / 'failures' / f'random_{res["seed"]}.yaml').write_text(
                yaml.safe_dump(res['data'], sort_keys=False))
    for key, value in summary.items():
        print(f'{key}: {value}')
    return 0 if not failed else 1


if __name__ == '__main__':
    raise SystemExit(main())
