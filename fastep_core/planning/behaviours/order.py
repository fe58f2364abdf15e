"""A navigator's behaviours, one object each with the state it keeps, in the order a tick asks them."""

from __future__ import annotations

from fastep_core.kinematics.model import RobotModel
from fastep_core.planning.behaviours.arrival import Arrival, BackToGoal
from fastep_core.planning.behaviours.checks import PathCheck, ProgressCheck, TrapCheck
from fastep_core.planning.behaviours.driving import Algorithm
from fastep_core.planning.behaviours.recoveries import BackingUp, Escaping, HoldBreaker, Manoeuvring
from fastep_core.planning.behaviours.tick import FloatArray, Steering, Tick
from fastep_core.planning.limits import Limits
from fastep_core.planning.params import PlannerParams

__all__ = ['Behaviours']


class Behaviours:
    """The behaviours of one navigator. `command` asks them in order; the first that answers gives the tick's
    command, and the algorithm (`choose_target`) answers last. The recoveries are asked before the algorithm, so a
    robot backing up or escaping goes on with it whatever the algorithm would choose."""

    def __init__(self, model: RobotModel, radius: float, params: PlannerParams, limits: Limits) -> None:
        self.arrival = Arrival()
        self.back_to_goal = BackToGoal(self.arrival)
        self.path_check = PathCheck()
        self.progress_check = ProgressCheck()
        self.escaping = Escaping()
        self.backing_up = BackingUp(model, limits, manoeuvres=not model.turns_in_place)
        # A robot that cannot turn in place leaves traps and tight spots by manoeuvres of its own arcs.
        self.manoeuvring = None if model.turns_in_place else \
            Manoeuvring(model, radius, params, self.escaping, self.backing_up)
        self.trap_check = TrapCheck(self.manoeuvring, self.escaping)
        self.hold_breaker = HoldBreaker(self.backing_up)
        self.algorithm = Algorithm()
        self.in_order = tuple(b for b in (
            self.arrival, self.back_to_goal, self.path_check, self.progress_check, self.trap_check,
            self.manoeuvring, self.backing_up, self.hold_breaker, self.escaping) if b is not None)

    def command(self, nav: Steering, now: Tick) -> FloatArray:
        for behaviour in self.in_order:
            command = behaviour(nav, now)
            if command is not None:
                return command
        return self.algorithm(nav, now)

    def new_goal(self) -> None:
        self.arrival.new_goal()
        self.path_check.new_goal()
        self.hold_breaker.new_goal()
        self.escaping.new_goal()
        if self.manoeuvring is not None:
            self.manoeuvring.new_goal()

    def restart_clock(self, model: RobotModel, limits: Limits) -> None:
        """Every timer afresh on a switched clock (the goal stays)."""
        self.hold_breaker.new_goal()
        self.escaping.escape.stop()
        self.backing_up.restart_clock(model, limits)
        if self.manoeuvring is not None:
            self.manoeuvring.driver.reset()

    def retune(self, model: RobotModel, params: PlannerParams, limits: Limits) -> None:
        self.backing_up.retune(model, limits)
        if self.manoeuvring is not None:   # a tractor-trailer's: its model does not saturate
            self.manoeuvring.driver.params = params
