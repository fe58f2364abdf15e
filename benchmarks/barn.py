"""The BARN score on dense clutter: the Jackal declared as a 0.22 m circle, or with its real box, judged by the box.

    python -m benchmarks.barn [--worlds 25] [--first 0] [--realtime [FACTOR]] [--algorithm fastep_route] [--seed 0]
                              [--json FILE]

World k is world FAMILY_SEED0 + k of `dense_clutter_laser` (the robot a 0.22 m circle) and of
`dense_clutter_jackal` (the same world, the robot declared with JACKAL_FOOTPRINT: planned with its circumscribed
0.333 m circle), obstacles only in the laser (experiments/dense_clutter.py). Each run is fastep_core.simulator
.simulate with `realtime` (default 1.0: planning time is the robot's time, as fastep-sim --realtime), and every
step's pose is judged twice against the true world: by the Jackal's box placed at the pose (what Gazebo counts as
a collision) and by the 0.22 m circle.

The BARN challenge's score (Perille et al., 2020; Xiao et al., the BARN challenge at ICRA): per run
success x OT / clip(AT, 2 OT, 8 OT), with OT the optimal path length over the maximum speed and AT the
traversal time; a run that does not arrive, or whose box touches anything, scores 0
(fastep_core.metrics.barn_score). So a run scores at most 0.5 (AT at or below 2 OT). OT here: the exact shortest
path keeping the 0.22 m circle clear (fastep_core.planning.shortest_path.optimal.shortest_path) at the family's 2 m/s,
the same for both declarations.
Not deterministic with a realtime factor: it depends on the machine and its load.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from fastep_core.cli import realtime_factor
from fastep_core.experiments.dense_clutter import JACKAL_FOOTPRINT, ROBOT_RADIUS
from fastep_core.experiments.random_worlds import FAMILY_SEED0, random_family_data
from fastep_core.footprint import Footprint
from fastep_core.metrics import barn_score, trajectory_margins
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.scenario import Scenario, parse_scenario
from fastep_core.simulator import Tick, simulate

__all__ = ['DECLARATIONS', 'BarnRun', 'judged_run', 'main']

DECLARATIONS = {'circle': 'dense_clutter_laser', 'footprint': 'dense_clutter_jackal'}
"""How the robot is declared -> the family whose worlds declare it so (the same worlds)."""
BOX = Footprint.parse(JACKAL_FOOTPRINT)
SLOW = 0.5   # m/s: below this a step counts to its reason's slow time (crawling, backing up, stopped, escaping)


@dataclass(frozen=True)
class BarnRun:
    """One run, judged by the box and by the circle, and its BARN score."""

    world: int
    declared: str               # 'circle' | 'footprint'
    arrived: bool
    touched_by_box: bool        # the Jackal's box overlapped an obstacle at some step
    touched_by_circle: bool     # the 0.22 m circle did
    box_clearance: float        # the smallest signed clearance of the box (m)
    circle_clearance: float     # ... of the 0.22 m circle
    traversal_time: float | None   # AT (s), when it arrived
    optimal_time: float         # OT (s)
    score: float
    status: str
    wall_time: float            # seconds this run took here
    slow_time: dict[str, float]   # seconds below SLOW m/s, by the navigator's reason (where time goes)


def _scenario(declared: str, world: int) -> Scenario:
    seed = FAMILY_SEED0 + world
    return parse_scenario(random_family_data(DECLARATIONS[declared], seed), default_name=f'barn_{seed}')


def judged_run(declared: str, world: int, realtime: float | None = 1.0, algorithm: str = 'fastep_route',
               seed: int = 0) -> BarnRun:
    """World `world` driven with the robot declared as `declared`, every step's pose judged by box and circle."""
    scenario = _scenario(declared, world)
    (spec,) = scenario.robots
    rows: list[list[float]] = []
    slow: dict[str, float] = {}
    step = scenario.planner.dt

    def observe(tick: Tick) -> None:
        rows.append([tick.t, float(tick.state[0]), float(tick.state[1]), float(tick.state[2])])
        if abs(float(tick.command[0])) < SLOW:
            reason = tick.navigator.reason.split(';')[0][:60]
            slow[reason] = slow.get(reason, 0.0) + step

    started = time.perf_counter()
    run = simulate(scenario, algorithm, seed, observer=observe, realtime=realtime)
    wall = time.perf_counter() - started
    robot = run.robots[0]
    obstacles = scenario.world.obstacles
    box = float(trajectory_margins([rows], [BOX.radius], obstacles, footprints=[BOX]).obstacles[0])
    circle = float(trajectory_margins([rows], [ROBOT_RADIUS], obstacles).obstacles[0])
    path = shortest_path(scenario.world, spec.start[:2], spec.goal, ROBOT_RADIUS)
    optimal = float('nan') if path is None else path.length / scenario.planner.max_speed
    return BarnRun(world, declared, robot.reached, box < 0.0, circle < 0.0, box, circle, robot.sim_time, optimal,
                   barn_score(robot.reached, box < 0.0, robot.sim_time, optimal), robot.status, wall,
                   {k: round(v, 2) for k, v in sorted(slow.items(), key=lambda kv: -kv[1])})


def _summary(runs: list[BarnRun]) -> dict[str, object]:
    scores = np.array([r.score for r in runs])
    slow: dict[str, float] = {}
    for r in runs:
        for reason, seconds in r.slow_time.items():
            slow[reason] = slow.get(reason, 0.0) + seconds
    return {'runs': len(runs), 'arrived': sum(r.arrived for r in runs),
            'touched_by_box': sum(r.touched_by_box for r in runs),
            'touched_by_circle': sum(r.touched_by_circle for r in runs),
            'mean_score': float(scores.mean()) if len(scores) else float('nan'),
            'median_at_over_ot': float(np.median([r.traversal_time / r.optimal_time for r in runs
                                                  if r.traversal_time is not None] or [float('nan')])),
            'worst_box_clearance': min((r.box_clearance for r in runs), default=float('nan')),
            'slow_time': {k: round(v, 2) for k, v in sorted(slow.items(), key=lambda kv: -kv[1])}}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='barn', description=__doc__.splitlines()[0])
    p.add_argument('--worlds', type=int, default=25, help='worlds FIRST..FIRST+N-1 of the families (default 25)')
    p.add_argument('--first', type=int, default=0, help='the first world (default 0; e.g. 25: worlds not tuned on)')
    p.add_argument('--realtime', type=realtime_factor, nargs='?', const=1.0, default=1.0, metavar='FACTOR',
                   help='planning latency counted, x FACTOR (default 1.0); --lock-step for none')
    p.add_argument('--lock-step', action='store_true', help='the clock waits for the planner (no latency)')
    p.add_argument('--algorithm', default='fastep_route')
    p.add_argument('--seed', type=int, default=0, help="the runs' seed (default 0)")
    p.add_argument('--declared', nargs='+', choices=sorted(DECLARATIONS), default=['circle', 'footprint'])
    p.add_argument('--json', type=Path, help='write every run and the summaries as JSON')
    args = p.parse_args(argv)
    realtime = None if args.lock_step else args.realtime
    print(f'load average at start: {" ".join(f"{v:.2f}" for v in os.getloadavg())}', flush=True)
    runs: dict[str, list[BarnRun]] = {d: [] for d in args.declared}
    for world in range(args.first, args.first + args.worlds):
        for declared in args.declared:
            r = judged_run(declared, world, realtime, args.algorithm, args.seed)
            runs[declared].append(r)
            at = '-' if r.traversal_time is None else f'{r.traversal_time:.2f}'
            print(f'world {world:2d} {declared:9s} arrived {r.arrived!s:5s} box {r.box_clearance:+.3f} '
                  f'circle {r.circle_clearance:+.3f} AT {at:>6s} OT {r.optimal_time:.2f} score {r.score:.3f} '
                  f'({r.wall_time:.1f} s) {r.status[:50]}', flush=True)
    print(f'load average at end: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')
    summaries = {d: _summary(rs) for d, rs in runs.items()}
    print('| declared | arrived | touched by box | touched by circle | mean score | median AT/OT | worst box '
          'clearance (m) |')
    print('|---|---|---|---|---|---|---|')
    for declared, s in summaries.items():
        print(f'| {declared} | {s["arrived"]}/{s["runs"]} | {s["touched_by_box"]} | {s["touched_by_circle"]} | '
              f'{s["mean_score"]:.3f} | {s["median_at_over_ot"]:.2f} | {s["worst_box_clearance"]:+.3f} |')
    for declared, s in summaries.items():
        slow_time = s['slow_time']
        assert isinstance(slow_time, dict)
        print(f'{declared}: seconds below {SLOW} m/s by reason: ' +
              '; '.join(f'{k} {v:.1f}' for k, v in list(slow_time.items())[:6]))
    if args.json:
        args.json.write_text(json.dumps({'realtime': realtime, 'algorithm': args.algorithm, 'summaries': summaries,
                                         'runs': {d: [asdict(r) for r in rs] for d, rs in runs.items()}},
                                        indent=1) + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
