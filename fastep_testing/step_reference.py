"""The step fitness written plainly: the reference `fastep_core.planning.step.StepProblem.terms` is checked against.

This is eq. 10 and the clearance rule as they read in planning/step.py's docstring, one numpy expression per
term over every obstacle and every other robot, nothing skipped or reused (the form StepProblem.terms had
before it was made fast). The fast version skips terms it can prove to be exactly 0.0, reuses what two terms
share and writes into fewer temporaries, and must return the same floats bit for bit, because the swarm
compares them (tests/fastep_core/planning/test_step_terms.py). The product never calls this module.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import norm, point_segment_distance
from fastep_core.planning.step import StepProblem

__all__ = ['reference_terms']

FloatArray = NDArray[np.float64]


def reference_terms(problem: StepProblem, X: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(eq. 10 fitness, total constraint violation) of each candidate (m, 2), as StepProblem.terms."""
    p = problem
    obstacles = p.world.obstacles
    path_clearance = min(p.clearance, float(obstacles.clearance(p.origin))) - 1e-9
    others_gap = np.hypot(*(p.others - p.origin).T) if len(p.others) else np.zeros(0)
    path_robot_clearance = np.minimum(p.robot_clearance, others_gap) - 1e-9
    local = obstacles.distances(p.origin) < p.step_radius + p.clearance
    local_obstacles = obstacles.subset(local)

    X = np.asarray(X, dtype=float)
    x, y = X[:, 0], X[:, 1]
    viol = np.maximum(norm(x - p.origin[0], y - p.origin[1]) - p.step_radius, 0.0)
    viol += np.maximum(p.clearance - p.world.wall_distance(X), 0.0)
    f = p.c * norm(x - p.target[0], y - p.target[1])
    if len(obstacles):
        dist = obstacles.distance_rows(x, y)
        f += p.a / np.maximum(dist.sum(axis=0), 1e-9)
        if len(local_obstacles):
            viol += np.maximum(p.clearance - dist[local].min(axis=0), 0.0)
            run = local_obstacles.fan_clearance(p.origin, X)
            viol += np.maximum(path_clearance - run, 0.0)
    if len(p.others):
        gap = norm(x[:, None] - p.others[:, 0], y[:, None] - p.others[:, 1])
        f += p.b / np.maximum(gap.sum(axis=1), 1e-9)
        viol += np.maximum(p.robot_clearance - gap, 0.0).sum(axis=1)
        run = point_segment_distance(p.others, p.origin, X[:, None, :])
        viol += np.maximum(path_robot_clearance - run, 0.0).sum(axis=1)
    for ox, oy in p.pass_on_right:
        viol += np.maximum(ox * (y - p.origin[1]) - oy * (x - p.origin[0]), 0.0)
    return f, viol
