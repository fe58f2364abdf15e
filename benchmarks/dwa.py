"""DWA's parameters measured: arrival, collisions, path / exact optimum and CPU per setting, on fixed worlds.

    python -m benchmarks.dwa [--config '{"dwa_clearance": 0.5}' ...] [--random 1 2 5 9 11 12 13] [--u-traps 0]
                             [--algorithm dwa]

Each --config (JSON planner overrides; '{}' is the defaults) runs `dwa` once (it draws no random numbers) on
table2_s1-s3, case_study_1-2, the given random worlds (fastep_core.experiments.random_worlds, point masses only) and
U-trap worlds (u_trap_scenario_data seeds 0..N-1), one process. Prints one line per setting: robots arrived
without collision, collisions, path / exact optimum (mean, worst) and simulated seconds per optimal metre over
the arrivals, the smallest margin kept, and CPU seconds of the whole setting. How the defaults of the `dwa_*`
parameters were chosen: docs/benchmarks.md ("DWA"). --algorithm runs another planner (seed 0) on the same worlds.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from typing import Sequence

import numpy as np

from fastep_core import cli
from fastep_core.errors import ParameterError
from fastep_core.experiments.random_worlds import random_scenario_data, u_trap_scenario_data
from fastep_core.planning.algorithms import ALGORITHMS
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.scenario import Scenario, load_scenario, parse_scenario
from fastep_core.simulator import simulate

BUILT_IN = ('table2_s1', 'table2_s2', 'table2_s3', 'case_study_1', 'case_study_2')
RANDOM = (1, 2, 5, 9, 11, 12, 13)


def worlds(random: Sequence[int], u_traps: int) -> dict[str, Scenario]:
    out = {name: load_scenario(name) for name in BUILT_IN}
    out.update({f'random_{s}': parse_scenario(random_scenario_data(s, tractor_share=0.0)) for s in random})
    out.update({f'u_trap_{s}': parse_scenario(u_trap_scenario_data(s)) for s in range(u_traps)})
    return out


def measure(scenarios: dict[str, Scenario], overrides: dict[str, float], algorithm: str = 'dwa') -> str:
    arrived = total = collided = 0
    ratios: list[float] = []
    pace: list[float] = []
    margin = np.inf
    cpu = time.process_time()
    for scenario in scenarios.values():
        scenario = dataclasses.replace(scenario, planner=scenario.planner.with_overrides(overrides))
        run = simulate(scenario, algorithm, 0)
        for spec, robot in zip(scenario.robots, run.robots):
            best = shortest_path(scenario.world, spec.start[:2], spec.goal,
                                 spec.radius + scenario.planner.clearance_margin)
            total += 1
            collided += robot.collided
            margin = min(margin, robot.min_clearance)
            if robot.reached and not robot.collided and best is not None:
                arrived += 1
                ratios.append(robot.path_length / best.length)
                pace.append((robot.sim_time or 0.0) / best.length)
    cpu = time.process_time() - cpu
    return (f'{algorithm} {json.dumps(overrides):40s} arrived {arrived}/{total}, collided {collided}, path/opt mean '
            f'{np.mean(ratios):.4f} worst {np.max(ratios):.3f}, {np.mean(pace):.3f} s per optimal m, '
            f'min margin {margin:.3f} m, CPU {cpu:.1f} s')


def main(argv: Sequence[str] | None = None) -> int:
    prog = 'python -m benchmarks.dwa'
    p = cli.Parser(prog=prog, description=__doc__.splitlines()[0])
    p.add_argument('--config', nargs='+', default=['{}'], help='JSON planner overrides per setting')
    p.add_argument('--random', nargs='*', type=cli.seed, default=list(RANDOM), help='random world seeds')
    p.add_argument('--u-traps', type=int, default=0, help='U-trap worlds, seeds 0..N-1')
    p.add_argument('--algorithm', choices=ALGORITHMS, default='dwa', help='planner (default dwa; seed 0)')

    def run() -> int:
        args = p.parse_args(argv)
        try:
            configs = [json.loads(text) for text in args.config]
        except json.JSONDecodeError as exc:
            raise ParameterError(f'--config must be JSON: {exc}') from None
        scenarios = worlds(args.random, args.u_traps)
        print(f'{len(scenarios)} worlds; load average ' + ' '.join(f'{v:.2f}' for v in os.getloadavg()))
        for overrides in configs:
            print(measure(scenarios, overrides, args.algorithm), flush=True)
        return 0
    return cli.guard(prog, run)


if __name__ == '__main__':
    raise SystemExit(main())
