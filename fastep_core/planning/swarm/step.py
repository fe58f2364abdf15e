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
import itertools
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Callable, Generator, Iterator

import numpy as np
from numpy.typing import NDArray

from fastep_core.errors import ParameterError
from fastep_core.geometry import point_segment_distance
from fastep_core.optimize import OptimizeResult, aco_r, fastep_iterations
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.swarm.step_arrays import DistanceRows, near_row_sum
from fastep_core.world import World

__all__ = ['INFEASIBLE', 'StepPlan', 'StepProblem', 'StepRun', 'plan_step', 'plan_step_passing_right',
           'recorded_step_problems', 'rule_calls', 'step_run']

FloatArray = NDArray[np.float64]
INFEASIBLE = 1e6
FEASIBLE_ONLY_FROM = 128
"""StepProblem.fitness computes eq. 10 for the feasible candidates only from this many candidates on (an
attraction call); for fewer (the initial swarm, stepping ahead) one pass over every row costs less."""
RULE_CALLS = 9
"""Objective calls (FAStep: the initial swarm and four iterations) a step plan keeping right of the robots ahead
is given to find a feasible candidate before the step is planned without that rule (plan_step_passing_right).
With merged_moves (one call per iteration) the same four iterations: rule_calls()."""


def rule_calls(params: PlannerParams, method: str = 'fastep') -> int:
    """RULE_CALLS for this swarm: the initial swarm and the same iterations, whatever an iteration's calls."""
    return 1 + (RULE_CALLS - 1) // 2 if method == 'fastep' and params.merged_moves else RULE_CALLS


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
        self._local = self.world.obstacles.distances(self.origin) < self.step_radius + self.clearance
        self._prepare_terms()

    def bounds(self) -> FloatArray:
        return np.stack([self.origin - self.step_radius, self.origin + self.step_radius], axis=1)

    def _prepare_terms(self) -> None:
        """Constants of terms(): everything that depends on the problem but not on the candidates."""
        obstacles = self.world.obstacles
        self._ox, self._oy = float(self.origin[0]), float(self.origin[1])
        # The points each candidate's offset (x - px, y - py) is taken from, one row each: the origin (the run),
        # the target (eq. 5), the circles' centres (eq. 6-7), then the walls' starts (the minimum distance
        # technique); the distance itself is taken for all but the walls' starts.
        nc = obstacles.n_circles
        self._all_rows = DistanceRows(np.concatenate([self.origin[None], self.target[None]]), obstacles,
                                      np.arange(len(obstacles)))
        # The local obstacles (the clearance rule): their rows alone, after the origin's, for fitness().
        local = np.flatnonzero(self._local)
        self._local_rows = local
        self._near_rows = DistanceRows(self.origin[None], obstacles, local)
        # The local obstacles relative to the origin, as Obstacles.fan_clearance has them: the points whose
        # distance to each run is measured (circle centres, then wall starts, then wall ends).
        lc, ls = local[local < nc], local[local >= nc]
        self._run_circles, self._run_walls = len(lc), ls
        centres, starts, ends = (obstacles.centers[lc] - self.origin, obstacles.starts[ls - nc] - self.origin,
                                 obstacles.ends[ls - nc] - self.origin)
        points = np.concatenate([centres, starts, ends])
        self._run_px, self._run_py = points[:, 0, None], points[:, 1, None]
        self._run_radii = obstacles.radii[lc][:, None]
        sx, sy, ex, ey = starts[:, 0, None], starts[:, 1, None], ends[:, 0, None], ends[:, 1, None]
        self._run_sx, self._run_sy, self._run_ex, self._run_ey = sx, sy, ex, ey
        self._run_wx, self._run_wy = ex - sx, ey - sy
        self._run_side = self._run_wy * sx - self._run_wx * sy
        self._run_from_origin = point_segment_distance(self.origin, obstacles.starts[ls - nc],
                                                       obstacles.ends[ls - nc])[:, None]
        # Candidates within this distance of the origin keep `clearance` from the workspace border (with room
        # for the rounding of their distances): the border term is 0.0 for them.
        xmin, ymin, xmax, ymax = self.world.workspace
        slack = 1e-6 + 1e-9 * (max(abs(v) for v in self.world.workspace) + float(np.abs(self.origin).max()))
        self._border_free_reach = min(self._ox - xmin, xmax - self._ox, self._oy - ymin, ymax - self._oy) - \
            self.clearance - slack
        self._other_x, self._other_y = self.others[:, 0], self.others[:, 1]
        rel = self.others - self.origin
        self._other_rel_x, self._other_rel_y = rel[:, 0, None], rel[:, 1, None]

    def terms(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(eq. 10 fitness, total constraint violation) of each candidate; violation 0 means feasible.

        Fast and exact: the same floats, bit for bit, as the plain formulation in
        fastep_testing/step_reference.py (the swarm compares them, so a different last bit would change its
        moves). What makes it fast: a term proven to be 0.0 for every candidate is skipped (adding 0.0 changes
        nothing); what two terms share (the run vectors, the distances to the local walls) is computed once;
        constants are prepared once per problem. Every sum keeps its order and its array shape (numpy sums
        rows of an (n, m) array one after another, rows of an (m, n) array pairwise).
        """
        X = np.asarray(X, dtype=float)
        x, y = X[:, 0], X[:, 1]
        # Row 0: the run origin -> X (the step radius, the runs' clearance, the traffic rule); row 1: the
        # target; rows 2...: the obstacles (circles, then walls), as Obstacles.distance_rows.
        rows, dx, dy, run2 = self._distance_rows(x, y)
        viol, reach_max = self._reach_violation(X, rows[0])
        f = np.multiply(rows[1], self.c)
        if len(self.world.obstacles):
            dist = rows[2:]
            total = dist.sum(axis=0)
            np.maximum(total, 1e-9, out=total)
            f += np.divide(self.a, total, out=total)
            if len(self._local_rows):
                local = self._local_rows
                nearest = dist[local[0]] if len(local) == 1 else dist[local].min(axis=0)
                viol += np.maximum(np.subtract(self.clearance, nearest), 0.0)
                run = self._run_clearance(dx, dy, run2, dist[self._run_walls])
                np.subtract(self._path_clearance, run, out=run)
                viol += np.maximum(run, 0.0, out=run)
        if len(self.others):
            gap, total = self._robot_distances(x, y)
            f += np.divide(self.b, total, out=total)
            self._add_robot_gap_violation(viol, reach_max, x, y, gap)
            self._add_robot_run_violation(viol, dx, dy, run2, reach_max)
        for ox, oy in self.pass_on_right:
            # cross(other - origin, X - origin) > 0 means X is left of the line toward the other robot.
            viol += np.maximum(ox * dy - oy * dx, 0.0)
        return f, viol

    def _distance_rows(self, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Distance of each candidate to the origin, the target and each obstacle surface: (2 + n_obstacles, m);
        and the run vectors x - ox, y - oy and their squared length (views valid until the next call)."""
        return self._all_rows(x, y)

    def _run_clearance(self, dx: FloatArray, dy: FloatArray, run2: FloatArray, walls_rows: FloatArray) -> FloatArray:
        """Closest approach of each run origin -> X to a local obstacle surface: Obstacles.fan_clearance.

        The minimum is taken in another order (minima are exact in any order); the distances from the run
        ends to the local walls are `walls_rows` (one row per local wall, in order).
        """
        inv_length2 = np.maximum(run2, 1e-300)
        np.divide(1.0, inv_length2, out=inv_length2)
        # Distance from each point (a circle's centre, a wall's end) to each run: (points, m).
        t = self._run_px * dx
        t += self._run_py * dy
        t *= inv_length2
        np.maximum(t, 0.0, out=t)
        np.minimum(t, 1.0, out=t)
        to_run = t * dx
        np.subtract(self._run_px, to_run, out=to_run)
        t *= dy
        np.subtract(self._run_py, t, out=t)
        to_run *= to_run
        t *= t
        to_run += t
        np.sqrt(to_run, out=to_run)
        nc, walls = self._run_circles, self._run_walls
        if nc:
            circles = to_run[:nc]
            circles -= self._run_radii
            run: FloatArray = circles[0] if nc == 1 else circles.min(axis=0)
            if not len(walls):
                return run
        ns = len(walls)
        d = np.minimum(to_run[nc:nc + ns], to_run[nc + ns:])
        np.minimum(d, walls_rows, out=d)
        np.minimum(d, self._run_from_origin, out=d)
        # A run that properly crosses a wall: the wall's ends lie strictly on either side of the run and the
        # run's ends strictly on either side of the wall.
        sx, sy, ex, ey = self._run_sx, self._run_sy, self._run_ex, self._run_ey
        a = dx * sy
        a -= dy * sx
        b = dx * ey
        b -= dy * ex
        a *= b
        crossing = a < 0.0
        b = np.subtract(dy, sy, out=b)
        b *= self._run_wx
        c = np.subtract(dx, sx, out=a)
        c *= self._run_wy
        b -= c
        b *= self._run_side
        crossing &= b < 0.0
        np.copyto(d, 0.0, where=crossing)
        nearest: FloatArray = d[0] if ns == 1 else d.min(axis=0)
        if nc:
            np.minimum(run, nearest, out=nearest)
        return nearest

    def _reach_violation(self, X: FloatArray, reach: FloatArray) -> tuple[FloatArray, float]:
        """The violation of the step radius (reach: origin -> each candidate) and of the clearance from the
        workspace border (measured only when some candidate reaches past where it is proven kept), and the
        farthest reach."""
        viol = reach - self.step_radius
        np.maximum(viol, 0.0, out=viol)
        reach_max = float(reach.max(initial=0.0))
        if reach_max > self._border_free_reach:
            viol += np.maximum(self.clearance - self.world.wall_distance(X), 0.0)
        return viol, reach_max

    def _robot_distances(self, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Each candidate's distance to each other robot (m, n_others), and their sums (at least 1e-9: f2's
        denominator, eq. 9), computed in place in this order so the floats are those of the plain formulation."""
        gap = self._robot_gaps(x[:, None], y[:, None], self._other_x, self._other_y)
        total = gap.sum(axis=1)
        np.maximum(total, 1e-9, out=total)
        return gap, total

    @staticmethod
    def _robot_gaps(x: FloatArray, y: FloatArray, other_x: FloatArray, other_y: FloatArray) -> FloatArray:
        """hypot(x - other_x, y - other_y), broadcast, by the operations of the plain formulation (one element's
        float does not depend on the array's layout)."""
        gap = x - other_x
        gap *= gap
        gy = y - other_y
        gy *= gy
        gap += gy
        np.sqrt(gap, out=gap)
        return gap

    def _add_robot_gap_violation(self, viol: FloatArray, reach: float, x: FloatArray, y: FloatArray,
                                 gap: FloatArray | None = None) -> None:
        """viol += sum over the other robots of how far each candidate comes inside the robot's clearance.

        A robot whose centre is farther from the origin than `reach` plus its clearance is out of every
        candidate's way: its column of the (m, n_others) sum is 0.0 (in a crowd, most of them), and only the
        others are added, in the order numpy's row sum would add them (step_arrays.sparse_row_sum), to the same bits.
        `gap`: the candidates' distances to every robot when the caller has them (terms: f2 needs them all);
        otherwise only the robots in reach are measured.
        """
        near = np.flatnonzero(self._other_gap - reach < self.robot_clearance + self._slack)
        if len(near) == len(self.others):
            if gap is None:
                gap = self._robot_gaps(x[:, None], y[:, None], self._other_x, self._other_y)
            viol += np.maximum(self.robot_clearance - gap, 0.0).sum(axis=1)
            return
        if gap is None:   # (near, m): the rows near_row_sum takes
            rows = self._robot_gaps(x, y, self._other_x[near][:, None], self._other_y[near][:, None])
        else:
            rows = gap[:, near].T
        rows = np.maximum(np.subtract(self.robot_clearance[near][:, None], rows), 0.0)
        total = near_row_sum(near, rows, len(self.others))
        if total is not None:
            viol += total

    def _add_robot_run_violation(self, viol: FloatArray, dx: FloatArray, dy: FloatArray, run2: FloatArray,
                                 reach: float) -> None:
        """viol += sum over the other robots of how far each run origin-X comes inside the robot's clearance.

        As geometry.point_segment_distance(others, origin, X) computes it, for the robots a run can reach;
        the others' columns are 0.0, as in _add_robot_gap_violation.
        """
        near = np.flatnonzero(self._other_gap - reach < self._path_robot_clearance + self._slack)
        if not len(near):
            return
        qx, qy = self._other_rel_x[near], self._other_rel_y[near]
        t = qx * dx
        t += qy * dy
        t /= np.where(run2 > 0.0, run2, 1.0)
        np.maximum(t, 0.0, out=t)
        np.minimum(t, 1.0, out=t)
        u = t * dx
        np.subtract(qx, u, out=u)
        t *= dy
        np.subtract(qy, t, out=t)
        u *= u
        t *= t
        u += t
        np.sqrt(u, out=u)                                     # (near, m): distance of each run to each robot
        np.subtract(self._path_robot_clearance[near][:, None], u, out=u)
        np.maximum(u, 0.0, out=u)
        total = near_row_sum(near, u, len(self.others))
        if total is not None:
            viol += total

    def fitness(self, X: FloatArray) -> FloatArray:
        """What the swarm minimises: eq. 10 where feasible, INFEASIBLE + violation elsewhere.

        np.where(viol > 0, INFEASIBLE + viol, f) of terms(), the same floats, but eq. 10 is computed for the
        feasible candidates only: its sum over every obstacle (f1) is most of the work, and most candidates
        of an attraction move are infeasible (on the families' worlds ~80 %: pulled past the brighter
        firefly, out of the step disk; in a 16-robot crowd 92 %). The violation needs the local obstacles' rows
        alone, and the distances to the robots in reach (~6 of 15 there); f2's distances to every robot are
        taken for the feasible candidates. Every value is computed by the expressions of terms(), in the same
        order.
        """
        X = np.asarray(X, dtype=float)
        if len(X) < FEASIBLE_ONLY_FROM:
            f, viol = self.terms(X)
            return np.where(viol > 0.0, INFEASIBLE + viol, f)
        x, y = X[:, 0], X[:, 1]
        near, dx, dy, run2 = self._near_rows(x, y)   # row 0: the run origin -> X; then the local obstacles
        viol, reach_max = self._reach_violation(X, near[0])
        if len(self.world.obstacles) and len(self._local_rows):
            dist = near[1:]
            nearest = dist[0] if len(dist) == 1 else dist.min(axis=0)
            viol += np.maximum(np.subtract(self.clearance, nearest), 0.0)
            run = self._run_clearance(dx, dy, run2, dist[self._run_circles:])
            np.subtract(self._path_clearance, run, out=run)
            viol += np.maximum(run, 0.0, out=run)
        if len(self.others):   # the violation needs the robots in reach alone; f2 (below) every robot
            self._add_robot_gap_violation(viol, reach_max, x, y)
            self._add_robot_run_violation(viol, dx, dy, run2, reach_max)
        for ox, oy in self.pass_on_right:
            viol += np.maximum(ox * dy - oy * dx, 0.0)
        out: FloatArray = np.add(INFEASIBLE, viol)
        feasible = np.flatnonzero(~(viol > 0.0))
        if len(feasible):
            # numpy sums the rows of a one-column array pairwise, of a wider one one row after another: a lone
            # feasible candidate (among many, here) is evaluated twice, so its f1 is summed as terms() sums it.
            take = feasible if len(feasible) > 1 else np.repeat(feasible, 2)
            rows = self._all_rows(x[take], y[take])[0]
            f = np.multiply(rows[1], self.c)
            if len(self.world.obstacles):
                total = rows[2:].sum(axis=0)
                np.maximum(total, 1e-9, out=total)
                f += np.divide(self.a, total, out=total)
            if len(self.others):
                total = self._robot_distances(x[take], y[take])[1]
                f += np.divide(self.b, total, out=total)
            out[feasible] = f[:len(feasible)]
        return out


@dataclass(frozen=True)
class StepPlan:
    """A planned waypoint, its fitness and the optimizer's result."""

    waypoint: FloatArray
    cost: float
    result: OptimizeResult


class _GaveUp(Exception):
    """A plan found no feasible candidate in the objective calls it was given (plan_step's feasible_within)."""


def plan_step(problem: StepProblem, params: PlannerParams, rng: np.random.Generator,
              method: str = 'fastep', feasible_within: int | None = None) -> StepPlan | None:
    """Minimise the step fitness with FAStep (or ACO_R); None when no feasible waypoint was found.

    feasible_within: raise _GaveUp once that many objective calls have found no feasible candidate.
    """
    run = StepRun(problem, params, rng, method, feasible_within)
    run.advance()
    if run.gave_up:
        raise _GaveUp
    return run.plan


class StepRun:
    """One step plan that may be spread over several control ticks: `advance(iterations)` runs at most that many
    swarm iterations (the first call also the initial swarm) and says whether the plan is done; `plan` is then
    plan_step's result. Run to the end in one call it is plan_step, draw for draw.

    Why: in a crowd one step plan is the slowest part of a control tick (docs/benchmarks.md), and a planner with a
    budget per tick (PlannerParams.step_iterations) finishes it over the next ticks instead. FAStep only: ACO_R
    (the baseline) runs whole on the first call. With feasible_within, a plan whose swarm has found no feasible
    candidate in that many objective calls ends there: done, `gave_up`, no plan.
    """

    def __init__(self, problem: StepProblem, params: PlannerParams, rng: np.random.Generator,
                 method: str = 'fastep', feasible_within: int | None = None) -> None:
        if method not in ('fastep', 'aco'):
            raise ParameterError(f'unknown step optimizer {method!r} (fastep or aco)')
        for recorder in _recorders:
            recorder.append(copy.copy(problem))   # as posed: plan_step_passing_right reassigns pass_on_right
        self.problem, self.params, self.rng, self.method = problem, params, rng, method
        self.fitness = problem.fitness if feasible_within is None else \
            _feasible_within(problem.fitness, feasible_within)
        self._iterations: Generator[None, None, OptimizeResult] | None = None
        self.result: OptimizeResult | None = None
        self.gave_up = False
        self._error: Exception | None = None   # what ended the run otherwise (raised again by every advance)

    @property
    def done(self) -> bool:
        return self.result is not None or self.gave_up

    @property
    def plan(self) -> StepPlan | None:
        """The planned step once done; None before, and when no feasible waypoint was found."""
        result = self.result
        if result is None or not result.fun < INFEASIBLE:
            return None
        return StepPlan(np.asarray(result.x, dtype=float), float(result.fun), result)

    def advance(self, iterations: int | None = None) -> bool:
        """Run at most `iterations` swarm iterations (None: to the end); True when the plan is done.

        An exception from the objective (or bad parameters, found at the first call) ends the run: it is raised
        here and again by every later call, never taken for an unfinished plan."""
        if self._error is not None:
            raise self._error
        if self.done:
            return True
        params = self.params
        try:
            if self.method == 'aco':
                self.result = aco_r(self.fitness, self.problem.bounds(), archive_size=params.aco_archive,
                                    n_ants=params.aco_ants, q=params.aco_q, xi=params.aco_xi,
                                    max_iter=params.aco_iter, patience=params.patience, tol=params.tol, rng=self.rng)
                return True
            if self._iterations is None:
                self._iterations = fastep_iterations(
                    self.fitness, self.problem.bounds(), n_fireflies=params.n_fireflies, max_iter=params.max_iter,
                    patience=params.patience, gamma=params.gamma, beta0=params.beta0, alpha=params.alpha,
                    alpha_damping=params.alpha_damping, tol=params.tol, rng=self.rng,
                    attraction_sample=params.attraction_sample or None, merged_moves=bool(params.merged_moves))
                next(self._iterations)            # the initial swarm: it pauses before the first iteration
            for _ in itertools.repeat(None) if iterations is None else range(iterations):
                next(self._iterations)
        except StopIteration as finished:
            self.result = finished.value
        except _GaveUp:
            self.gave_up = True
        except Exception as exc:
            self._error = exc
            raise
        return self.done


def _feasible_within(fitness: Callable[[FloatArray], FloatArray], calls: int) -> Callable[[FloatArray], FloatArray]:
    """fitness, raising _GaveUp at its `calls`-th call if no call has returned a feasible value."""
    made = 0
    feasible = False

    def bounded(X: FloatArray) -> FloatArray:
        nonlocal made, feasible
        values = fitness(X)
        made += 1
        feasible = feasible or bool((values < INFEASIBLE).any())
        if not feasible and made >= calls:
            raise _GaveUp
        return values
    return bounded


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


def step_run(problem: StepProblem, params: PlannerParams, rng: np.random.Generator, method: str,
             ahead: FloatArray) -> StepRun:
    """A StepRun keeping right of the robots met `ahead` (offsets from the robot), given RULE_CALLS objective calls to
    find a feasible candidate (plan_step_passing_right says why); a plain one when `ahead` is empty."""
    if not len(ahead):
        return StepRun(problem, params, rng, method)
    problem.pass_on_right = ahead
    return StepRun(problem, params, rng, method, feasible_within=rule_calls(params, method))


def plan_step_passing_right(problem: StepProblem, params: PlannerParams, rng: np.random.Generator, method: str,
                            ahead: FloatArray, plain_after: bool = True) -> StepPlan | None:
    """plan_step keeping right of the robots met `ahead` (offsets from the robot) when that is possible at all;
    two robots meeting head-on otherwise keep making mirror-image side steps into each other's way.

    "Possible" is decided within RULE_CALLS objective calls: a swarm that has found no candidate keeping right
    by then is stopped and the step is planned without the rule. Where the rule leaves no feasible step (robots
    ahead on every side, in a crowd) the swarm has no feasible point to stall on and kept shrinking the
    violation until max_iter: 15-60 calls, the most expensive plans there were, each followed by the plan
    without the rule. In a 16-robot crowd a quarter of the rule's plans failed so, and 97 % of those that
    succeeded had found a feasible candidate within 9 calls (91 % within 5; with 5, one of 30 worlds of the
    2-4 robot family came out 8 % longer, with 9 none changed its path / optimum mean or worst).
    With plain_after False a rule that gives up returns None: the caller plans without it when it chooses
    (the navigator, on the next control tick).
    """
    if len(ahead):
        try:
            run = step_run(problem, params, rng, method, ahead)
            run.advance()
        finally:
            problem.pass_on_right = np.zeros((0, 2))
        step = run.plan
        if step is not None or not plain_after:
            return step
    return plan_step(problem, params, rng, method)
