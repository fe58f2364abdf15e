"""One planned step: the eq. 10 fitness with a hard clearance rule, minimised by a swarm.

f = a / f1 + b / f2 + c * d (eq. 10), f1 = sum of distances to the obstacles (eq. 6-7; surface distances,
so circles and line segments are measured alike by the minimum distance technique), f2 = sum of distances to
the other robots (eq. 8-9; the term is dropped when there are none), d = distance to the robot's target
(eq. 5). With the paper's magnitudes c * d dominates, so f alone does not keep a robot safe; a candidate is
feasible only if
- it lies within `step_radius` of the robot and inside the workspace by `clearance`,
- it and the straight run to it keep `clearance` from every obstacle surface,
- it and the run to it keep `robot_clearance[k]` from every other robot's centre,
- it lies to the right of the line from the robot to each robot in `pass_on_right` (a traffic rule: two
  robots meeting head-on make mirror-image decisions, and without a shared convention they sidestep into
  each other's way again and again; keeping right makes mirror images pass each other).
Infeasible candidates score 1e6 + total violation, so any feasible candidate beats every infeasible one and
the swarm is still pulled toward feasibility.
"""

from __future__ import annotations

import copy
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Iterator

import numpy as np
from numpy.typing import NDArray

from fastep_core.errors import ParameterError
from fastep_core.geometry import norm, point_segment_distance
from fastep_core.optimize import OptimizeResult, aco_r, fastep
from fastep_core.planning.params import PlannerParams
from fastep_core.world import World

__all__ = ['INFEASIBLE', 'StepPlan', 'StepProblem', 'plan_step', 'plan_step_passing_right', 'recorded_step_problems']

FloatArray = NDArray[np.float64]
INFEASIBLE = 1e6


@dataclass
class StepProblem:
    """Everything one robot's swarm needs to score candidate waypoints at one moment."""

    world: World
    origin: FloatArray               # robot position (x, y)
    target: FloatArray               # where the robot wants to end up (its goal)
    clearance: float                 # required distance from obstacle surfaces (radius + margin)
    step_radius: float
    a: float = 0.18
    b: float = 0.18
    c: float = 0.01
    others: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))       # other robots' centres
    robot_clearance: FloatArray = field(default_factory=lambda: np.zeros(0))   # required centre distance
    pass_on_right: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))  # robots to keep right of

    def __post_init__(self) -> None:
        self.origin = np.asarray(self.origin, dtype=float)
        self.target = np.asarray(self.target, dtype=float)
        self.others = np.asarray(self.others, dtype=float).reshape(-1, 2)
        self.robot_clearance = np.asarray(self.robot_clearance, dtype=float).reshape(-1)
        self.pass_on_right = np.asarray(self.pass_on_right, dtype=float).reshape(-1, 2) - self.origin
        # A robot already closer than required (a trailer swing, another robot approaching) must still be
        # allowed to move away: the run may not get any closer than it is now.
        here = self.world.obstacles.clearance(self.origin)
        self._path_clearance = min(self.clearance, float(here)) - 1e-9
        gap = np.hypot(*(self.others - self.origin).T) if len(self.others) else np.zeros(0)
        self._path_robot_clearance = np.minimum(self.robot_clearance, gap) - 1e-9
        self._other_gap = gap
        scale = float(np.abs(self.others).max(initial=0.0)) + float(np.abs(self.origin).max())
        self._slack = 1e-6 + 1e-9 * scale   # rounding of the runs' distances, with room to spare
        # Only obstacles that reach into the step disk (plus clearance) can violate the clearance rule; the
        # swarm evaluates thousands of candidates per step, so the rule is checked against those alone.
        obstacles = self.world.obstacles
        self._local = obstacles.distances(self.origin) < self.step_radius + self.clearance
        self._local_obstacles = obstacles.subset(self._local)

    def bounds(self) -> FloatArray:
        return np.stack([self.origin - self.step_radius, self.origin + self.step_radius], axis=1)

    def terms(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(eq. 10 fitness, total constraint violation) of each candidate; violation 0 means feasible."""
        X = np.asarray(X, dtype=float)
        x, y = X[:, 0], X[:, 1]
        viol = np.maximum(norm(x - self.origin[0], y - self.origin[1]) - self.step_radius, 0.0)
        viol += np.maximum(self.clearance - self.world.wall_distance(X), 0.0)
        f = self.c * norm(x - self.target[0], y - self.target[1])
        if len(self.world.obstacles):
            dist = self.world.obstacles.distance_rows(x, y)
            f += self.a / np.maximum(dist.sum(axis=0), 1e-9)
            if len(self._local_obstacles):
                viol += np.maximum(self.clearance - dist[self._local].min(axis=0), 0.0)
                run = self._local_obstacles.fan_clearance(self.origin, X)
                viol += np.maximum(self._path_clearance - run, 0.0)
        if len(self.others):
            gap = norm(x[:, None] - self.others[:, 0], y[:, None] - self.others[:, 1])
            f += self.b / np.maximum(gap.sum(axis=1), 1e-9)
            viol += np.maximum(self.robot_clearance - gap, 0.0).sum(axis=1)
            viol += self._robot_run_violation(X)
        for ox, oy in self.pass_on_right:
            # cross(other - origin, X - origin) > 0 means X is left of the line toward the other robot.
            viol += np.maximum(ox * (y - self.origin[1]) - oy * (x - self.origin[0]), 0.0)
        return f, viol

    def _robot_run_violation(self, X: FloatArray) -> FloatArray:
        """Sum over the other robots of how far each run origin-X comes inside the robot's clearance.

        A robot farther from the origin than the farthest candidate by more than its clearance cannot reach
        any run: its column is 0.0, as measuring it gave (in a crowd, most of them). The columns stay in
        place, so each row is summed in the same order as before, to the same bits.
        """
        reach = float(norm(X[:, 0] - self.origin[0], X[:, 1] - self.origin[1]).max(initial=0.0))
        near = self._other_gap - reach < self._path_robot_clearance + self._slack
        if near.all():
            run = point_segment_distance(self.others, self.origin, X[:, None, :])
            total: FloatArray = np.maximum(self._path_robot_clearance - run, 0.0).sum(axis=1)
            return total
        columns = np.zeros((len(X), len(self.others)))
        if near.any():
            run = point_segment_distance(self.others[near], self.origin, X[:, None, :])
            columns[:, near] = np.maximum(self._path_robot_clearance[near] - run, 0.0)
        total = columns.sum(axis=1)
        return total

    def fitness(self, X: FloatArray) -> FloatArray:
        """What the swarm minimises: eq. 10 where feasible, INFEASIBLE + violation elsewhere."""
        f, viol = self.terms(X)
        return np.where(viol > 0.0, INFEASIBLE + viol, f)


@dataclass(frozen=True)
class StepPlan:
    """A planned waypoint, its fitness and the optimizer's result."""

    waypoint: FloatArray
    cost: float
    result: OptimizeResult


def plan_step(problem: StepProblem, params: PlannerParams, rng: np.random.Generator,
              method: str = 'fastep') -> StepPlan | None:
    """Minimise the step fitness with FAStep (or ACO_R); None when no feasible waypoint was found."""
    for recorder in _recorders:
        recorder.append(copy.copy(problem))   # as posed: plan_step_passing_right reassigns pass_on_right
    if method == 'fastep':
        result = fastep(problem.fitness, problem.bounds(), n_fireflies=params.n_fireflies,
                        max_iter=params.max_iter, patience=params.patience, gamma=params.gamma,
                        beta0=params.beta0, alpha=params.alpha, alpha_damping=params.alpha_damping, tol=params.tol,
                        rng=rng)
    elif method == 'aco':
        result = aco_r(problem.fitness, problem.bounds(), archive_size=params.aco_archive,
                       n_ants=params.aco_ants, q=params.aco_q, xi=params.aco_xi, max_iter=params.aco_iter,
                       patience=params.patience, tol=params.tol, rng=rng)
    else:
        raise ParameterError(f'unknown step optimizer {method!r} (fastep or aco)')
    if not result.fun < INFEASIBLE:
        return None
    return StepPlan(np.asarray(result.x, dtype=float), float(result.fun), result)


_recorders: list[list[StepProblem]] = []


@contextmanager
def recorded_step_problems() -> Iterator[list[StepProblem]]:
    """Collect every StepProblem plan_step is given inside the block, in order (benchmarks replay them).

    A problem is recorded as it was posed (a shallow copy: plan_step_passing_right sets and resets its
    pass_on_right). Recording does not change what is planned.
    """
    problems: list[StepProblem] = []
    _recorders.append(problems)
    try:
        yield problems
    finally:
        _recorders[:] = [r for r in _recorders if r is not problems]


def plan_step_passing_right(problem: StepProblem, params: PlannerParams, rng: np.random.Generator, method: str,
                            ahead: FloatArray) -> StepPlan | None:
    """plan_step keeping right of the robots met `ahead` (offsets from the robot) when that is possible at all;
    two robots meeting head-on otherwise keep making mirror-image side steps into each other's way."""
    if len(ahead):
        problem.pass_on_right = ahead
        step = plan_step(problem, params, rng, method)
        problem.pass_on_right = np.zeros((0, 2))
        if step is not None:
            return step
    return plan_step(problem, params, rng, method)
