"""Benchmark: what a crowd's slowest control ticks are made of, in fastep-sim (issue 16's planner p99).

    python -m benchmarks.crowd_ticks [--robots 16] [--algorithm fastep_route] [--seeds 0 1] [--window 5 15]

The live benchmark (`benchmarks.graph_scaling --counts 16`) reports the worst planner's control-callback p99
over its last 200 ticks: a robot's second- or third-slowest tick. This runs the same circle of robots
in-process and times every `Navigator.update` (wall, perf_counter), with the part of it spent in step plans
(`Navigator.plan_time`) and in exact paths (`FAStepRoute.route_time`: the first route, replans, escapes). Per
seed: the run's CPU, the robots' paths summed and when the last robot was home; over the window (simulated
seconds; graph_scaling's live window is 5-15 s): each robot's p99 and third-slowest tick, and what every
robot's three slowest ticks were made of: a step plan, a route, both or neither (the rest of the tick).
The machine is shared: run the variants to compare one after the other, more than once, and say the load.
"""

from __future__ import annotations

import argparse
import os
import time
from collections import Counter
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Iterator

import numpy as np
import yaml

from fastep_core.planning.navigator import Navigator
from fastep_core.scenario import parse_scenario
from fastep_core.simulator import simulate
from fastep_testing.runs import circle_yaml

SLOWEST = 3   # a robot's ticks whose make-up is reported: its p99 over 200 ticks lies between the 2nd and 3rd


@dataclass
class Tick:
    t: float          # simulated time
    wall: float       # seconds in Navigator.update
    plan: float       # ... of them in step plans
    route: float      # ... in exact paths


@dataclass
class Timing:
    ticks: dict[int, list[Tick]] = field(default_factory=dict)   # by navigator


@contextmanager
def timed_updates() -> Iterator[Timing]:
    """Every Navigator.update inside the block, timed per navigator (the method is restored after)."""
    timing = Timing()
    original = Navigator.update

    def update(self: Navigator, t: float, *args: Any, **kwargs: Any) -> Any:
        plan, route = self.plan_time, getattr(self, 'route_time', 0.0)
        start = time.perf_counter()
        command = original(self, t, *args, **kwargs)
        wall = time.perf_counter() - start
        timing.ticks.setdefault(id(self), []).append(
            Tick(t, wall, self.plan_time - plan, getattr(self, 'route_time', 0.0) - route))
        return command

    Navigator.update = update   # type: ignore[method-assign]  # timed for this block only
    try:
        yield timing
    finally:
        Navigator.update = original   # type: ignore[method-assign]  # restored


def make_up(tick: Tick) -> str:
    """What a tick's time went to: 'step plan', 'route', 'both' or 'neither' (more than 0.5 ms of each counts)."""
    plan, route = tick.plan > 5e-4, tick.route > 5e-4
    return 'both' if plan and route else 'step plan' if plan else 'route' if route else 'neither'


def run(robots: int, algorithm: str, seed: int, window: tuple[float, float],
        step_iterations: int = 0) -> dict[str, Any]:
    scenario = parse_scenario(yaml.safe_load(circle_yaml(robots, 20.0, 2.0, step_iterations)))
    cpu = time.process_time()
    with timed_updates() as timing:
        result = simulate(scenario, algorithm, seed)
    cpu = time.process_time() - cpu
    p99, third, kinds = [], [], Counter[str]()
    for ticks in timing.ticks.values():
        seen = [k for k in ticks if window[0] <= k.t < window[1]]
        if len(seen) < SLOWEST:
            continue
        walls = np.array([k.wall for k in seen]) * 1e3
        p99.append(float(np.percentile(walls, 99)))
        slowest = sorted(seen, key=lambda k: -k.wall)[:SLOWEST]
        third.append(slowest[-1].wall * 1e3)
        kinds.update(make_up(k) for k in slowest)
    return {'seed': seed, 'cpu_s': cpu, 'arrived': sum(r.reached for r in result.robots),
            'paths_m': sum(r.path_length for r in result.robots),
            'last_home_s': max((r.sim_time or 0.0) for r in result.robots),
            'p99_ms': sorted(p99), 'third_ms': sorted(third), 'slowest_ticks': dict(kinds)}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog='python -m benchmarks.crowd_ticks', description=__doc__.split('\n')[0])
    parser.add_argument('--robots', type=int, default=16)
    parser.add_argument('--algorithm', default='fastep_route')
    parser.add_argument('--seeds', type=int, nargs='+', default=[0, 1])
    parser.add_argument('--step-iterations', type=int, default=0, metavar='K',
                        help='PlannerParams.step_iterations (default 0: a step plan in one tick)')
    parser.add_argument('--window', type=float, nargs=2, default=(5.0, 15.0), metavar=('FROM', 'TO'))
    args = parser.parse_args(argv)
    print(f'crowd_ticks: {args.robots} robots, {args.algorithm}, step_iterations {args.step_iterations}, '
          f'window {args.window[0]:g}-{args.window[1]:g} s; '
          f'load average {", ".join(f"{x:.2f}" for x in os.getloadavg())}', flush=True)
    for seed in args.seeds:
        r = run(args.robots, args.algorithm, seed, tuple(args.window), args.step_iterations)
        worst = r['p99_ms'][-1] if r['p99_ms'] else float('nan')
        median = float(np.median(r['p99_ms'])) if r['p99_ms'] else float('nan')
        third = r['third_ms'][-1] if r['third_ms'] else float('nan')
        print(f'seed {seed}: CPU {r["cpu_s"]:.2f} s, arrived {r["arrived"]}/{args.robots}, paths {r["paths_m"]:.1f} m, '
              f'last home {r["last_home_s"]:.1f} s; Navigator.update p99 worst {worst:.2f} ms, median robot '
              f'{median:.2f} ms; worst third-slowest tick {third:.2f} ms; the robots\' {SLOWEST} slowest ticks: '
              f'{", ".join(f"{k} {n}" for k, n in sorted(r["slowest_ticks"].items()))}', flush=True)


if __name__ == '__main__':
    main()
