"""Driving a tractor-trailer's manoeuvre: when to search one, replaying it tick by tick, when to search again.

A forward-steered vehicle cannot follow a point path out of a tight corner. A trapped tractor-trailer, or one
the guard keeps stopped (planning/recovery/back_up.py), drives a manoeuvre instead: a hybrid-A* search over its own
forward and reverse arcs (planning/recovery/manoeuvre_search.py) to where the goal is in clear sight ahead. Its commands
are replayed open loop while the robot is where the manoeuvre expects it; off by more than OFF_MANOEUVRE (a late
command on a real graph) or held by the guard for 3 s (a robot in the way), it is searched again from where
the robot is. A failed search is not repeated for RETRY_MANOEUVRE seconds.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
from numpy.typing import NDArray

from fastep_core.errors import ParameterError
from fastep_core.kinematics.model import RobotModel
from fastep_core.kinematics.tractor_trailer import TractorTrailer, wrap_angle
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.recovery.back_up import HOLD_BEFORE_STEP
from fastep_core.planning.recovery.manoeuvre_search import Manoeuvre, plan_manoeuvre
from fastep_core.world import World

__all__ = ['OFF_MANOEUVRE', 'RETRY_MANOEUVRE', 'ManoeuvreDriver']

FloatArray = NDArray[np.float64]
OFF_MANOEUVRE = 0.3     # m or rad: a robot this far off its manoeuvre's states searches it again
RETRY_MANOEUVRE = 5.0   # seconds without a search after one found nothing


class ManoeuvreDriver:
    """The manoeuvre being driven, if any, and the bookkeeping around its searches."""

    def __init__(self, model: RobotModel, radius: float, params: PlannerParams) -> None:
        if not isinstance(model, TractorTrailer):   # the search integrates eq. 13
            raise ParameterError(f'no manoeuvre search for a {type(model).__name__}')
        self.model, self.radius, self.params = model, radius, params
        self.count = 0                          # manoeuvres found (replans included)
        self.current: Manoeuvre | None = None   # the manoeuvre being driven ...
        self.tick = 0                           # ... and the tick of it that comes next
        self.retry_at = -math.inf               # no search before this time (after a failed one)
        self.left_at = math.inf                 # distance to the goal where the last manoeuvre ended
        self.held_since: float | None = None    # since when the guard holds the manoeuvre

    @property
    def active(self) -> bool:
        return self.current is not None

    @property
    def status(self) -> str:
        assert self.current is not None
        return f'manoeuvring: {self.current.arcs} arcs, {self.current.reversals} reversals'

    def reset(self) -> None:
        """A new goal: nothing driven, nothing to wait for."""
        self.current, self.retry_at, self.left_at = None, -math.inf, math.inf

    def plan(self, world: World, state: FloatArray, goal: FloatArray, t: float) -> bool:
        """Search a manoeuvre from state to where the goal is in clear sight ahead; True if one was found.

        It keeps the radius plus a quarter margin from the obstacles of `world` (robots parked included; a
        robot already nearer gets no nearer), and no tick of it gets nearer within the radius, which the guard
        would stop. A manoeuvre ends where the goal is in clear sight; if kinematic driving from there got
        stuck again before coming progress_distance nearer, "in sight" was not enough (it had looped hundreds
        of times in a soak scenario): the next one goes on until the goal is within reach.
        """
        if t < self.retry_at:
            return False
        p = self.params
        keep = self.radius + 0.25 * p.clearance_margin
        distance = math.hypot(goal[0] - state[0], goal[1] - state[1])
        again = distance > self.left_at - p.progress_distance
        clear_within = math.inf if again else self.radius + 0.5 * p.clearance_margin
        found = plan_manoeuvre(self.model, world, state, goal, keep, p.dt, floor=self.radius,
                               clear_within=clear_within, reach=max(1.0, p.goal_tolerance))
        if found is None or found.ticks == 0:
            self.current, self.retry_at = None, t + RETRY_MANOEUVRE
            return False
        self.count += 1
        self.current, self.tick, self.held_since = found, 0, None
        return True

    def drive(self, state: FloatArray, t: float, distance: float, guard: Callable[[FloatArray], FloatArray],
              replan: Callable[[], bool]) -> tuple[FloatArray | None, bool]:
        """(this tick's command as `guard(command)` lets it through, or None; whether the manoeuvre ended here).

        None without an end: the robot was off course or held too long, and `replan()` found no new one.
        """
        if self.over(distance):
            return None, True
        if self.off_course(state, t):
            self.retry_at = -math.inf
            if not replan():
                return None, False
        command = self.command()
        guarded = guard(command)
        self.advance(t, guarded is command)
        return guarded, False

    def over(self, distance: float) -> bool:
        """Has every tick been driven? Then it ends here, `distance` from the goal."""
        assert self.current is not None
        if self.tick < self.current.ticks:
            return False
        self.current, self.left_at = None, distance
        return True

    def off_course(self, state: FloatArray, t: float) -> bool:
        """Is the robot too far off the expected state, or held too long, to go on replaying?"""
        assert self.current is not None
        expected = self.current.states[self.tick]
        off = max(math.hypot(state[0] - expected[0], state[1] - expected[1]),
                  abs(wrap_angle(float(state[2]) - float(expected[2]))))
        held = self.held_since is not None and t - self.held_since >= 3 * HOLD_BEFORE_STEP
        return off > OFF_MANOEUVRE or held

    def command(self) -> FloatArray:
        assert self.current is not None
        command: FloatArray = self.current.commands[self.tick]
        return command

    def advance(self, t: float, moved: bool) -> None:
        """The tick's command was driven (`moved`), or the guard held it."""
        if moved:
            self.tick += 1
            self.held_since = None
        elif self.held_since is None:
            self.held_since = t

