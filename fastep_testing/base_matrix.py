"""Bases by goals: the planner's defaults on bases that do not do what they are told (fastep_core/dynamics), in
fastep-sim, judged on the true trajectory.

Bases: the kinematic plant (what every other experiment drives) and the physics presets: `nominal` (14 kg, 2.5
m/s^2), `heavy` (40 kg on weak motors: it brakes at about 0.8 m/s^2), `limited_controller` (its controller
limited to 0.5 m/s^2, the planner not told), `slippery` (floor friction 0.3). Goals: `wall_ahead` (0.45 m before
a wall, straight ahead), `behind_wall` (round the end of a wall), `open_floor` (7 m ahead, nothing near) and
`heading` (the open floor's goal with a heading a quarter turn off the way there). Every goal must be reached,
stopped, within goal_tolerance, never touching anything, overshooting it by at most OVERSHOOT, with no loop (at
most LOOP metres driven after first reaching it), and a heading goal within yaw_goal_tolerance.

    python -m benchmarks.closed_loop          # the table (docs/benchmarks.md, "Bases that do not do as told")
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fastep_core.scenario import Scenario, parse_scenario
from fastep_core.simulator import simulate

__all__ = ['BASES', 'GOALS', 'LOOP', 'OVERSHOOT', 'BaseRun', 'goal_world', 'run_base']

BASES = ('kinematic', 'nominal', 'heavy', 'limited_controller', 'slippery')
GOALS = ('wall_ahead', 'behind_wall', 'open_floor', 'heading')
OVERSHOOT = 0.1   # m: the most a goal may be driven past (beyond it, along the way it was first reached)
LOOP = 1.0        # m: driven after first reaching the goal, more is a loop
RADIUS = 0.22     # m: a TurtleBot-class base
TOLERANCE = 0.1   # goal_tolerance's default


@dataclass
class BaseRun:
    """One base driven to one goal (module docstring): distances in m, speeds in m/s and rad/s, angles in rad."""

    base: str
    goal: str
    arrived: bool
    status: str
    time: float
    min_clearance: float
    final_distance: float
    overshoot: float
    after_reaching: float      # m driven after first reaching the goal
    heading_error: float       # NaN: a goal without a heading
    arrival_speed: float

    @property
    def ok(self) -> bool:
        heading = math.isnan(self.heading_error) or abs(self.heading_error) <= 0.25
        return self.arrived and self.min_clearance > 0.0 and self.final_distance <= TOLERANCE and \
            self.overshoot <= OVERSHOOT and self.after_reaching <= LOOP and heading

    def row(self) -> dict[str, Any]:
        return {'base': self.base, 'goal': self.goal, 'arrived': self.arrived, 'time': round(self.time, 2),
                'min_clearance': round(self.min_clearance, 3), 'final_distance': round(self.final_distance, 3),
                'overshoot': round(self.overshoot, 3), 'after_reaching': round(self.after_reaching, 3),
                'heading_error': None if math.isnan(self.heading_error) else round(self.heading_error, 3),
                'arrival_speed': round(self.arrival_speed, 3), 'ok': self.ok, 'status': self.status}


def goal_world(goal: str, base: str) -> Scenario:
    """The world of one goal, with one diff-drive robot on `base` (module docstring)."""
    room = [{'segment': {'start': list(a), 'end': list(b)}}
            for a, b in (((0.1, 0.1), (9.9, 0.1)), ((9.9, 0.1), (9.9, 7.9)), ((9.9, 7.9), (0.1, 7.9)),
                         ((0.1, 7.9), (0.1, 0.1)))]
    start, target, extra = [1.5, 4.0, 0.0], [8.5, 4.0], []
    if goal == 'wall_ahead':
        extra = [{'segment': {'start': [8.95, 2.0], 'end': [8.95, 6.0]}}]
    elif goal == 'behind_wall':
        extra = [{'segment': {'start': [5.0, 2.0], 'end': [5.0, 7.9]}}]
    elif goal == 'heading':
        target = [8.5, 4.0, math.pi / 2]
    elif goal != 'open_floor':
        raise KeyError(f'no goal {goal!r} (known: {", ".join(GOALS)})')
    robot: dict[str, Any] = {'name': 'r1', 'model': 'diff_drive', 'start': start, 'goal': target, 'radius': RADIUS}
    if base != 'kinematic':
        robot['dynamics'] = base
    return parse_scenario({'name': f'{goal}_{base}', 'workspace': [0.0, 0.0, 10.0, 8.0], 'obstacles': room + extra,
                           'robots': [robot], 'planner': {'max_sim_time': 90.0}})


def run_base(base: str, goal: str, algorithm: str = 'fastep_route', seed: int = 0) -> BaseRun:
    """One run of the matrix, judged on the true trajectory (fastep-sim's samples and velocities)."""
    scenario = goal_world(goal, base)
    run = simulate(scenario, algorithm, seed).robots[0]
    spec = scenario.robots[0]
    rows = np.asarray(run.trajectory, dtype=float)
    gx, gy = spec.goal
    distance = np.hypot(rows[:, 1] - gx, rows[:, 2] - gy)
    reached = np.flatnonzero(distance <= TOLERANCE)
    overshoot = after = 0.0
    if len(reached):
        first = int(reached[0])
        # Past the goal along the way it came in: (position - goal) on the unit vector of its approach.
        way = np.array([gx - rows[first, 1], gy - rows[first, 2]])
        way = way / max(float(np.hypot(*way)), 1e-9)
        overshoot = max(float(((rows[first:, 1] - gx) * way[0] + (rows[first:, 2] - gy) * way[1]).max()), 0.0)
        after = float(np.hypot(*np.diff(rows[first:, 1:3], axis=0).T).sum())
    heading_error = math.nan if spec.goal_heading is None else \
        math.remainder(float(rows[-1, 3]) - spec.goal_heading, math.tau)
    speed = math.hypot(run.velocity[-1][1], run.velocity[-1][2]) if run.velocity else 0.0
    return BaseRun(base, goal, run.reached, run.status, math.nan if run.sim_time is None else run.sim_time,
                   run.min_clearance, float(distance[-1]), overshoot if len(reached) else math.nan, after,
                   heading_error, speed)
