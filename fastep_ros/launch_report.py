"""What fastep-launch says and writes after a run (fastep_ros.launch): a line per robot (arrived or not, the path
measured from its odometry, the time, the smallest clearance kept, judged against the true world, by its outline
where it has a footprint), and --json /
--plot as fastep-sim writes them."""

from __future__ import annotations

import argparse
import json
import math

from fastep_core.cli import fail
from fastep_core.dynamic_world import DynamicWorld
from fastep_core.metrics import trajectory_margins
from fastep_core.scenario import Scenario
from fastep_ros.monitor import RobotLive

__all__ = ['SAMPLE_SPACING', 'report']

SAMPLE_SPACING = 0.05   # metres between trajectory rows written to --json, at least


def _min_clearance(scenario: Scenario, robots: dict[str, RobotLive]) -> dict[str, float]:
    """Smallest margin each robot kept (negative: collided), from its odometry, to the obstacles and the other
    robots (fastep_core.metrics; with simulated time every plant stamps odometry on the same grid)."""
    movers = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs).movers   # a v2 world's, over time
    # A robot with a footprint (a diff drive: its rows carry the heading) is judged by its outline at each pose.
    footprints = [robot.spec.footprint for robot in robots.values()]
    margins = trajectory_margins([[row[:4] if outline is not None else row[:3] for row in robot.rows]
                                  for robot, outline in zip(robots.values(), footprints)],
                                 [robot.spec.radius for robot in robots.values()], scenario.world.obstacles,
                                 movers if len(movers) else None, footprints)
    return {name: float(margin) for name, margin in zip(robots, margins.overall)}


def _sampled(rows: list[list[float]]) -> list[list[float]]:
    if len(rows) < 3:
        return rows
    out = [rows[0]]
    for row in rows[1:-1]:
        if math.hypot(row[1] - out[-1][1], row[2] - out[-1][2]) >= SAMPLE_SPACING:
            out.append(row)
    out.append(rows[-1])
    return out


def report(prog: str, args: argparse.Namespace, scenario: Scenario, robots: dict[str, RobotLive], t0: float,
           sim_time: bool) -> tuple[bool, bool]:
    """Print one line per robot, write --json / --plot; (did any robot collide, were the files written). `robots`:
    the monitor's, `t0` the simulated (or wall) time the run began at."""
    from fastep_core.simulator import RobotRun, Run

    clearance = _min_clearance(scenario, robots)
    runs = []
    for name, robot in robots.items():
        rows = [[r[0] - t0, *r[1:]] for r in robot.rows]
        when = f'{robot.end_time:.1f} s' if robot.end_time is not None else '-'
        collided = clearance[name] < 0.0
        print(f'{name}: {robot.outcome}{" COLLIDED" if collided else ""}, path {robot.path_length:.2f} m, '
              f'time {when}, min clearance {clearance[name]:.2f} m, activations {robot.activations} '
              f'({robot.reason})', flush=True)
        runs.append(RobotRun(name=name, model=robot.spec.model, reached=robot.outcome == 'arrived',
                             collided=collided, path_length=robot.path_length,
                             sim_time=robot.end_time if robot.outcome == 'arrived' else None,
                             min_clearance=clearance[name], activations=robot.activations,
                             escapes=robot.escapes, manoeuvres=robot.manoeuvres,
                             status=f'{robot.outcome}: {robot.reason}', trajectory=_sampled(rows),
                             waypoints=robot.waypoints))
    run = Run(args.seed, args.algorithm, runs)
    try:
        if args.json is not None:
            doc = {'scenario': scenario.name, 'algorithm': args.algorithm, 'live': True,
                   'rtf': None if not sim_time else args.rtf, 'runs': [run.to_json()]}
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps(doc) + '\n')
            print(f'wrote {args.json}')
        if args.plot is not None:
            from msg_tools.plots import plot_paths
            args.plot.parent.mkdir(parents=True, exist_ok=True)
            plot_paths(scenario, run, args.plot)
            print(f'wrote {args.plot}')
    except OSError as exc:
        fail(prog, f'cannot write output: {exc}')
        return any(r.collided for r in runs), False
    return any(r.collided for r in runs), True
