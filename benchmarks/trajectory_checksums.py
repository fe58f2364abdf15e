"""Checksums of fastep-sim trajectories: proof that a refactor changed no decision a robot takes.

    python -m benchmarks.trajectory_checksums [--seeds 3] [--algorithms fastep aco] [--out FILE.json]

For every built-in scenario (and with --u-traps / --random, generated ones that exercise trap escapes and
tractor-trailer manoeuvres), algorithm and seed it runs `fastep_core.simulator.simulate` (what `fastep-sim
--json` prints) and hashes, per run, everything but wall time: each robot's trajectory rows and waypoints
(first hash) and what is reported of it (reached, collided, path length, simulated time, clearance,
activations, escapes, manoeuvres, status; second hash). Run it before and after a change and compare the
JSON files (`diff`): equal hashes mean equal trajectories, bit for bit.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

from fastep_core.experiments.random_worlds import random_scenario_data, u_trap_scenario_data
from fastep_core.planning.algorithms import drives
from fastep_core.scenario import Scenario, builtin_names, load_scenario, parse_scenario
from fastep_core.simulator import simulate


def scenario_named(key: str) -> Scenario:
    """A built-in scenario by name, or 'u_trap:<model>:<seed>' / 'random:<seed>' from random_worlds."""
    kind, _, rest = key.partition(':')
    if kind == 'u_trap':
        model, _, seed = rest.partition(':')
        return parse_scenario(u_trap_scenario_data(int(seed), model))
    if kind == 'random':
        return parse_scenario(random_scenario_data(int(rest)))
    return load_scenario(key)


def run_digest(scenario: str, algorithm: str, seed: int) -> tuple[str, str]:
    """(trajectory hash, outcome hash) of one run: the rows and waypoints; the reported numbers and status."""
    run = simulate(scenario_named(scenario), algorithm=algorithm, seed=seed)
    paths, outcome = hashlib.sha256(), hashlib.sha256()
    for r in run.robots:
        paths.update(r.name.encode())
        paths.update(np.ascontiguousarray(np.asarray(r.trajectory, dtype=np.float64)).tobytes())
        paths.update(np.ascontiguousarray(np.asarray(r.waypoints, dtype=np.float64)).tobytes())
        outcome.update(repr((r.name, r.reached, r.collided, r.path_length, r.sim_time, r.min_clearance,
                             r.activations, r.escapes, r.manoeuvres, r.status)).encode())
    return paths.hexdigest()[:16], outcome.hexdigest()[:16]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='trajectory_checksums', description=__doc__.splitlines()[0])
    p.add_argument('--seeds', type=int, default=3, help='seeds 0..N-1 (default 3)')
    p.add_argument('--algorithms', nargs='+', default=['fastep', 'aco'])
    p.add_argument('--scenarios', nargs='+', default=None, help='default: every built-in scenario')
    p.add_argument('--u-traps', type=int, default=0, metavar='N',
                   help='also U-trap scenarios 0..N-1 of random_worlds, point mass and tractor-trailer')
    p.add_argument('--random', type=int, default=0, metavar='N', help='also random scenarios 0..N-1')
    p.add_argument('--out', type=Path, help='write the table as JSON')
    args = p.parse_args(argv)
    table: dict[str, list[str]] = {}
    scenarios = list(args.scenarios or builtin_names())
    scenarios += [f'u_trap:{model}:{i}' for i in range(args.u_traps) for model in ('point_mass', 'tractor_trailer')]
    scenarios += [f'random:{i}' for i in range(args.random)]
    for scenario in scenarios:
        models = {spec.model for spec in scenario_named(scenario).robots}
        for algorithm in args.algorithms:
            if not all(drives(algorithm, model) for model in models):
                continue   # dwa and a tractor-trailer: refused, nothing to compare
            for seed in range(args.seeds):
                key = f'{scenario} {algorithm} {seed}'
                table[key] = list(run_digest(scenario, algorithm, seed))
                print(f'{key:40s} {table[key][0]} {table[key][1]}', flush=True)
    if args.out:
        args.out.write_text(json.dumps(table, indent=1) + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
