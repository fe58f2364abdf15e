"""The step fitness written plainly: the reference `fastep_core.planning.swarm.step.StepProblem.terms` is checked
against.

This is eq. 10 and the clearance rule as they read in planning/swarm/step.py's docstring, one numpy expression per
term over every obstacle and every other robot: StepProblem.terms as it was before it was made fast (main at
537faf9, its robots-out-of-reach shortcut included). The fast version skips terms it can prove to be exactly
0.0, reuses what two terms share and writes into fewer temporaries, and must return the same floats bit for
bit, because the swarm compares them (tests/fastep_core/planning/swarm/test_step_terms.py); benchmarks/step_latency.py
times a step plan with both. The product never calls this module.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import norm, point_segment_distance
from fastep_core.planning.swarm.step import INFEASIBLE, StepProblem

__all__ = ['ReferenceTerms', 'reference_terms']

FloatArray = NDArray[np.float64]


class ReferenceTerms:
    """The plain eq. 10 of one StepProblem; what depends on the problem alone is computed once, as before."""

    def __init__(self, problem: StepProblem) -> None:
        p = self.problem = problem
        obstacles = p.world.obstacles
        self.path_clearance = min(p.clearance, float(obstacles.clearance(p.origin))) - 1e-9
        self.other_gap = np.hypot(*(p.others - p.origin).T) if len(p.others) else np.zeros(0)
        self.path_robot_clearance = np.minimum(p.robot_clearance, self.other_gap) - 1e-9
        scale = float(np.abs(p.others).max(initial=0.0)) + float(np.abs(p.origin).max())
        self.slack = 1e-6 + 1e-9 * scale
        self.local = obstacles.distances(p.origin) < p.step_radius + p.clearance
        self.local_obstacles = obstacles.subset(self.local)

    def terms(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(eq. 10 fitness, total constraint violation) of each candidate (m, 2), as StepProblem.terms."""
        p = self.problem
        obstacles = p.world.obstacles
        X = np.asarray(X, dtype=float)
        x, y = X[:, 0], X[:, 1]
        viol = np.maximum(norm(x - p.origin[0], y - p.origin[1]) - p.step_radius, 0.0)
        viol += np.maximum(p.clearance - p.world.wall_distance(X), 0.0)
        f = p.c * norm(x - p.target[0], y - p.target[1])
        if len(obstacles):
            dist = obstacles.distance_rows(x, y)
            f += p.a / np.maximum(dist.sum(axis=0), 1e-9)
            if len(self.local_obstacles):
                viol += np.maximum(p.clearance - dist[self.local].min(axis=0), 0.0)
                run = self.local_obstacles.fan_clearance(p.origin, X)
                viol += np.maximum(self.path_clearance - run, 0.0)
        if len(p.others):
            gap = norm(x[:, None] - p.others[:, 0], y[:, None] - p.others[:, 1])
            f += p.b / np.maximum(gap.sum(axis=1), 1e-9)
            viol += np.maximum(p.robot_clearance - gap, 0.0).sum(axis=1)
            viol += self.robot_run_violation(X)
        for ox, oy in p.pass_on_right:
            viol += np.maximum(ox * (y - p.origin[1]) - oy * (x - p.origin[0]), 0.0)
        return f, viol

    def robot_run_violation(self, X: FloatArray) -> FloatArray:
        """Sum over the other robots of how far each run origin-X comes inside the robot's clearance; a robot
        no run can reach keeps its column of 0.0 in place (the same bits as measuring it)."""
        p = self.problem
        reach = float(norm(X[:, 0] - p.origin[0], X[:, 1] - p.origin[1]).max(initial=0.0))
        near = self.other_gap - reach < self.path_robot_clearance + self.slack
        if near.all():
            run = point_segment_distance(p.others, p.origin, X[:, None, :])
            total: FloatArray = np.maximum(self.path_robot_clearance - run, 0.0).sum(axis=1)
            return total
        columns = np.zeros((len(X), len(p.others)))
        if near.any():
            run = point_segment_distance(p.others[near], p.origin, X[:, None, :])
            columns[:, near] = np.maximum(self.path_robot_clearance[near] - run, 0.0)
        total = columns.sum(axis=1)
        return total

    def fitness(self, X: FloatArray) -> FloatArray:
        f, viol = self.terms(X)
        return np.where(viol > 0.0, INFEASIBLE + viol, f)


def reference_terms(problem: StepProblem, X: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(eq. 10 fitness, total constraint violation) of each candidate (m, 2), as StepProblem.terms."""
    return ReferenceTerms(problem).terms(X)
