"""Physics bases on wall time localised by their wheel odometry alone: perception told the pose may drift, or not.

    python -m benchmarks.odometry_drift [--worlds office behind_wall thin_cylinders] [--dynamics slippery heavy]

Each run is the robot harness (fastep_testing/robot_harness.py: the planner node driving a MuJoCo base on wall
time, a 720-beam laser, the map of the world's walls) with no localizer, so the planner's map pose is the base's
wheel odometry. `told nothing`: localization_tolerance and odometry_drift zero; `defaults`: the planner's. One
JSON line per run: arrived, collided against the true world, the last status and reason, the time to the goal.
"""

from __future__ import annotations

import argparse
import json

from fastep_testing.robot_harness import run_world

TOLD_NOTHING = {'localization_tolerance': '[0.0, 0.0]', 'odometry_drift': '[0.0, 0.0]'}


def main() -> None:
    parser = argparse.ArgumentParser(prog='python -m benchmarks.odometry_drift', description=__doc__.split('\n')[0])
    parser.add_argument('--worlds', nargs='+', default=['office', 'behind_wall', 'thin_cylinders'])
    parser.add_argument('--dynamics', nargs='+', default=['slippery', 'heavy'])
    parser.add_argument('--timeout', type=float, default=120.0)
    args = parser.parse_args()
    for world in args.worlds:
        for dynamics in args.dynamics:
            for told, params in (('told nothing', TOLD_NOTHING), ('defaults', {})):
                result = run_world(world, dynamics=dynamics, timeout=args.timeout, planner_params=params)
                print(json.dumps({'world': world, 'dynamics': dynamics, 'told': told, 'arrived': result.arrived,
                                  'collided': result.collided, 'status': result.status,
                                  'reason': result.reason[:140], 'time': round(result.time_to_goal, 1)}),
                      flush=True)


if __name__ == '__main__':
    main()
