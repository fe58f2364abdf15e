"""When a navigator's swarm may plan a step, and what a step plan carries over from one tick to the next.

Why over ticks: a step is planned within a control tick, and the slowest ticks of a crowd were those with two swarm
runs in them (docs/benchmarks.md). So:
- after no feasible step, none is planned for RETRY_AFTER seconds (other robots may move away);
- a step that could not keep right of the robots ahead is planned without that rule on the next tick (`deferred`),
  as the same activation;
- with params.step_iterations a plan needing more iterations is finished on the next ticks: continued only on the
  very next tick, within PENDING_FOR seconds and in the same world (else planned afresh, and after a world change
  whole, so that a world changing every tick cannot keep a plan from ending);
- a tick given no iteration (step_budget 0) comes at most once in a row: every plan ends.
With robots ahead a step first keeps right of them (step.py, step_run). The step problem and its swarm run are
step.py; `plan_next_step` is the navigator's (navigator.py) step of one tick.
"""

from __future__ import annotations

import math
import time
from typing import Protocol, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.planning.mode import Mode
from fastep_core.planning.others import OtherRobot, robot_arrays
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.safety.yielding import Yielding
from fastep_core.planning.swarm.step import StepProblem, StepRun, step_run
from fastep_core.world import World

__all__ = ['PENDING_FOR', 'RETRY_AFTER', 'StepPlanner', 'StepPlanning', 'plan_next_step', 'start_step']

FloatArray = NDArray[np.float64]

RETRY_AFTER = 0.5   # seconds between step-planning attempts while no feasible step exists
PENDING_FOR = 0.5   # seconds a step plan left unfinished (params.step_iterations) may be continued, at most


class StepPlanning:
    """The state of a navigator's step planning between ticks (ticks: the navigator's count of control ticks)."""

    def __init__(self) -> None:
        self.retry_at = -math.inf          # no step planning before this time (after a failed attempt)
        self.rule_gave_up = -1             # the tick whose plan could not keep right
        self.pending: StepRun | None = None   # a step plan to be finished next tick (params.step_iterations)
        self.pending_tick = -1             # ... the tick that left it unfinished
        self.pending_t = -math.inf         # ... and its time
        self.idle_tick = -1                # the last tick whose step plan was given no iteration

    def new_goal(self) -> None:
        """A new goal: nothing deferred or unfinished carries over (the retry time and idle tick do)."""
        self.rule_gave_up = -1
        self.pending, self.pending_tick = None, -1

    def restart_clock(self) -> None:
        """The clock was switched: no time or tick of the other clock is kept."""
        self.retry_at = -math.inf
        self.rule_gave_up = self.pending_tick = -1
        self.pending = None

    def waiting(self, t: float | None) -> bool:
        """Is step planning paused after a failed attempt?"""
        return t is not None and t < self.retry_at

    def plain(self, tick: int) -> bool:
        """Is this tick's step the one without the keep-right rule (the rule gave up last tick)?"""
        return self.rule_gave_up == tick - 1

    def deferred(self, tick: int) -> bool:
        """Is this tick's step left for the next tick (the rule gave up, or the plan is unfinished)?"""
        return self.rule_gave_up == tick or self.pending_tick == tick

    def resumed(self, tick: int, t: float | None, world: World) -> tuple[StepRun | None, bool]:
        """The unfinished plan this tick continues (None: plan afresh), and whether the new one must run whole."""
        run, whole = self.pending, False
        if run is not None and (self.pending_tick != tick - 1 or t is None or t - self.pending_t > PENDING_FOR):
            run = None            # not continued on the very next tick: the robots it went round have moved
        elif run is not None and run.problem.world is not world:
            run, whole = None, True   # the world changed under it (a new obstacle): planned afresh, whole
        self.pending, self.pending_tick = None, -1
        return run, whole

    def budget(self, tick: int, budget: int | None, iterations: int) -> int | None:
        """This tick's swarm iterations: `budget`, but no iteration at most one tick in a row (then `iterations`)."""
        if budget == 0:
            if self.idle_tick == tick - 1:
                return iterations
            self.idle_tick = tick
        return budget

    def unfinished(self, run: StepRun, tick: int, t: float) -> None:
        """The plan needs more iterations: it is continued next tick."""
        self.pending, self.pending_tick, self.pending_t = run, tick, t

    def retry_later(self, t: float) -> None:
        """No feasible step now: the next attempt waits RETRY_AFTER."""
        self.retry_at = t + RETRY_AFTER


class StepPlanner(Protocol):
    """What a navigator (navigator.py) gives and keeps for its step of a tick."""

    goal: FloatArray | None
    world: World
    params: PlannerParams
    radius: float
    rng: np.random.Generator
    yielding: Yielding
    steps: StepPlanning
    step_method: str
    activations: int
    plan_time: float
    mode: Mode
    reason: str
    waypoint: FloatArray | None
    cost: float
    plan: list[FloatArray]
    _ticks: int
    _last_t: float | None

    @property
    def clearance(self) -> float: ...
    def step_budget(self) -> int | None: ...
    def step_target(self) -> FloatArray: ...


def plan_next_step(nav: StepPlanner, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
    """The navigator's step of this tick (eq. 3-10): its waypoint; None (and a status reason) when no feasible step
    exists, or when the step is finished on the next tick (`deferred`; the navigator drives on meanwhile)."""
    assert nav.goal is not None
    steps, tick = nav.steps, nav._ticks
    if steps.waiting(nav._last_t):
        return None
    run, whole = steps.resumed(tick, nav._last_t, nav.world)
    if run is None:
        run = start_step(nav, position, others)
    budget = steps.budget(tick, None if whole else nav.step_budget(), nav.params.step_iterations)
    start = time.perf_counter()
    done = run.advance(budget)
    nav.plan_time += time.perf_counter() - start
    if not done:
        steps.unfinished(run, tick, nav._last_t or 0.0)
        nav.mode, nav.reason = Mode.AVOIDING, 'planning a step (finished on the next tick)'
        return None
    step = run.plan
    if step is None and len(run.problem.pass_on_right):
        steps.rule_gave_up = tick
        nav.mode, nav.reason = Mode.AVOIDING, 'cannot keep right; planning the step without it'
        return None
    if step is None:
        # Nothing feasible now; other robots may move away. Retry later rather than every tick.
        steps.retry_later(nav._last_t or 0.0)
        nav.mode, nav.reason, nav.waypoint, nav.cost = Mode.AVOIDING, 'no valid step; waiting', None, 0.0
        return None
    nav.mode, nav.reason = Mode.AVOIDING, 'stepping around an obstacle'
    nav.waypoint, nav.cost = step.waypoint, step.cost
    nav.plan.append(step.waypoint)
    return step.waypoint


def start_step(nav: StepPlanner, position: FloatArray, others: Sequence[OtherRobot]) -> StepRun:
    """The step problem of this tick (eq. 10 toward the navigator's step_target, the robots as they are and as
    yielding predicts them) and its swarm run, keeping right of the robots ahead unless the rule gave up last tick
    (then this plan continues that activation)."""
    p = nav.params
    plain = nav.steps.plain(nav._ticks)
    target = nav.step_target()
    centres, sums = robot_arrays(others, nav.radius)
    centres, sums = nav.yielding.with_predictions(position, others, centres, sums,
                                                  p.step_radius / max(p.max_speed, 1e-6))
    problem = StepProblem(nav.world, position, target, nav.clearance, p.step_radius, p.a, p.b, p.c, centres,
                          sums + p.clearance_margin)
    offset = centres - position
    ahead = (np.hypot(*offset.T) - sums < p.sensing_range) & (offset @ (target - position) > 0)
    if plain:
        ahead[:] = False
    else:
        nav.activations += 1
    return step_run(problem, p, nav.rng, nav.step_method, offset[ahead])
