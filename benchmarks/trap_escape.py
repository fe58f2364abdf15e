"""Trap escape before/after: arrival rate on U-shaped traps without it (trap_timeout 0) and with it.

    python -m benchmarks.trap_escape --scenarios 100 --workers 2 [--models tractor_trailer]

The same scenarios (fastep_core.experiments.random_worlds.u_trap_scenario_data, seeds 0..N-1; point masses and
tractor-trailers) and the same run seeds for both settings; every run is one robot facing a U open towards
it, with the goal behind the U's back wall. Prints a table and writes out/trap_escape.json.
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

from fastep_core.experiments.random_worlds import u_trap_scenario_data
from fastep_core.scenario import parse_scenario
from fastep_core.simulator import simulate


def run_one(job: tuple[int, str, str, float | None]) -> dict[str, Any]:
    seed, model, algorithm, trap_timeout = job
    data = u_trap_scenario_data(seed, model)
    if trap_timeout is not None:
        data['planner'] = {'trap_timeout': trap_timeout}
    robot = simulate(parse_scenario(data), algorithm, seed).robots[0]
    return {'seed': seed, 'model': model, 'algorithm': algorithm, 'escape': trap_timeout is None,
            'reached': robot.reached, 'collided': robot.collided, 'escapes': robot.escapes,
            'sim_time': robot.sim_time, 'path_length': robot.path_length, 'min_clearance': robot.min_clearance,
            'status': robot.status}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--scenarios', type=int, default=100)
    p.add_argument('--algorithms', nargs='+', default=['fastep', 'aco'])
    p.add_argument('--models', nargs='+', default=['point_mass', 'tractor_trailer'],
                   choices=['point_mass', 'tractor_trailer'])
    p.add_argument('--workers', type=int, default=2)
    p.add_argument('--out', type=Path, default=Path('out/trap_escape.json'))
    args = p.parse_args()
    jobs = [(seed, model, algorithm, timeout) for model in args.models
            for algorithm in args.algorithms for timeout in (0.0, None) for seed in range(args.scenarios)]
    start = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(run_one, jobs, chunksize=4))
    table = []
    for model in args.models:
        for algorithm in args.algorithms:
            for escape in (False, True):
                sel = [r for r in rows if r['model'] == model and r['algorithm'] == algorithm and r['escape'] == escape]
                table.append({'model': model, 'algorithm': algorithm, 'trap_escape': escape, 'runs': len(sel),
                              'arrived': sum(r['reached'] for r in sel),
                              'collided': sum(r['collided'] for r in sel),
                              'escapes': sum(r['escapes'] for r in sel)})
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({'table': table, 'runs': rows,
                                    'wall_seconds': round(time.perf_counter() - start, 1)}, indent=1) + '\n')
    print(f'{"model":16} {"algorithm":9} {"escape":6} {"arrived":>12} {"collided":>8}')
    for row in table:
        print(f'{row["model"]:16} {row["algorithm"]:9} {"on" if row["trap_escape"] else "off":6} '
              f'{row["arrived"]:>5}/{row["runs"]:<6} {row["collided"]:>8}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
