"""The recoveries as behaviours, each owning its state: a tractor-trailer's manoeuvre, backing up when the guard
keeps the robot stopped, the hold breaker's step round a robot, and the escape along the exact path out of a trap.
The mechanisms themselves are planning/recovery/'s."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from fastep_core.kinematics.model import RobotModel
from fastep_core.planning.behaviours.driving import drive_on
from fastep_core.planning.behaviours.tick import FloatArray, Steering, Tick
from fastep_core.planning.limits import Limits
from fastep_core.planning.mode import Mode
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.recovery.back_up import (
    REVERSE_HORIZON,
    BackUp,
    StopTimer,
    backup_speed,
    free_room,
    reverse_free,
)
from fastep_core.planning.recovery.escape import ESCAPING, TrapEscape
from fastep_core.planning.recovery.manoeuvre_driver import ManoeuvreDriver
from fastep_core.planning.safety.guard import Stop
from fastep_core.planning.shortest_path.exact_path import parked_world
from fastep_core.planning.shortest_path.optimal import OptimalPath
from fastep_core.world import World

__all__ = ['BackingUp', 'Escaping', 'HoldBreaker', 'Manoeuvring']


class Escaping:
    """Along the exact path out of a trap (planning/recovery/escape.py), until the robot has left it; no path
    left: failed."""

    def __init__(self) -> None:
        self.escape = TrapEscape()

    def new_goal(self) -> None:
        self.escape.stop()

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        target = self.follow(nav, now) if self.escape.active else None
        if nav.failed:
            return np.zeros(2)
        return drive_on(nav, now, target) if self.escape.active else None

    def start(self, nav: Steering, world: World, position: FloatArray, distance: float, t: float,
              others: Sequence[OtherRobot] = ()) -> bool:
        """Leave a trap along the exact shortest path; False (and failed) if there is none."""
        path = nav.exact_path(position, others)
        if path is None:
            nav.fail_no_path(position)
            return False
        nav.escapes += 1
        self.escape.start(path, nav.path_world, t, min(distance, nav.trap.best) - nav.params.progress_distance, world)
        nav.waypoint, nav.committed = None, False
        nav.progress.made_progress(t)
        nav.mode, nav.reason = Mode.AVOIDING, ESCAPING
        return True

    def follow(self, nav: Steering, now: Tick) -> FloatArray | None:
        """The escape's target; None once the robot has left the trap, or failed with no path left.

        A step around another robot (the hold breaker) leaves the path, which is planned again after it; so does a
        change of the world the robot knows (a sensed obstacle) that brings an obstacle within radius + a quarter
        margin of the rest of the path (the path was planned round what the robot knew then).
        """
        position, distance, t, others, world = now.position, now.distance, now.t, now.others, now.world
        escape = self.escape
        if escape.left(distance):
            nav.trap.reset(t, distance)
            return None
        replan = nav.committed
        path = escape.path
        assert path is not None   # escaping
        if escape.known is not world:
            parked = parked_world(world, others, now.goal, nav.radius, nav.params) or world
            keep = min(path.keep, nav.radius + 0.25 * nav.params.clearance_margin) - 1e-6
            replan = not escape.adopt(world, parked, keep) or replan
        if nav.committed:
            if nav.keep_waypoint(position, others):
                return nav.waypoint
            nav.committed = False

        def plan() -> tuple[OptimalPath, World] | None:
            path = nav.exact_path(position, others)
            return None if path is None else (path, nav.path_world)

        target, progressed = escape.next_target(position, t, plan, nav.radius, nav.params, replan, world)
        if target is None:
            nav.fail_no_path(position)
            return None
        if progressed:
            nav.progress.made_progress(t)
        nav.mode, nav.reason = Mode.AVOIDING, ESCAPING
        return target


class BackingUp:
    """Kept stopped by the guard a while (StopTimer): back up (BackUp, Nav2's backup recovery), or, for a robot
    that cannot turn in place, a manoeuvre first; the backing up under way, guarded, until the guard stops it."""

    def __init__(self, model: RobotModel, limits: Limits, manoeuvres: bool) -> None:
        self.stops = StopTimer()
        self.backup = BackUp(model, backup_speed(limits))
        self.manoeuvres = manoeuvres   # a manoeuvre is tried before backing up

    def retune(self, model: RobotModel, limits: Limits) -> None:
        self.backup.model, self.backup.speed = model, backup_speed(limits)

    def restart_clock(self, model: RobotModel, limits: Limits) -> None:
        self.stops = StopTimer()
        self.backup = BackUp(model, backup_speed(limits))

    def guarded(self, nav: Steering, state: FloatArray, t: float, stop: Stop | None, moved: bool,
                others: Sequence[OtherRobot]) -> None:
        """A command drive_to sent through the guard: passed (`moved`), or stopped; stopped long enough, a
        recovery starts (the controller starts afresh after it)."""
        if moved:
            self.stops.moved(state[:2])
        elif self.stops.stopped(t, stop, state[:2]):
            nav.clear_target()
            if not (self.manoeuvres and nav.start_manoeuvre(state, t, others)):
                self.backup.start(t)

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        return self.drive(nav, now) if self.backup.active(now.t) else None

    def drive(self, nav: Steering, now: Tick) -> FloatArray:
        """The backing-up recovery's command (planning/recovery/back_up.py), guarded; it ends where the guard
        stops it."""
        state, dt, others, world = now.state, now.dt, now.others, now.world
        seen = nav.seen
        free = None if seen is None else (
            lambda command: reverse_free(nav.model, state, nav.radius, command, REVERSE_HORIZON, world, seen,
                                         (), nav.obstacle_margin, nav.footprint))
        backup = self.backup
        guarded = backup.drive(state, dt, lambda points: free_room(world, points, others),
                               lambda command: nav.guard(state, command, dt, others), free)
        if backup.looking:
            nav.reason = 'backing up: stuck; turning to see the space behind (no scan has seen it free)'
        elif backup.until > -math.inf:
            nav.reason = 'backing up: stuck'
        return guarded


class HoldBreaker:
    """Held by the guard for another robot a while (BackingUp's StopTimer): one step round it, driven to its end
    (the navigator's `committed`); a step deferred to the next tick (planning/swarm/step_planning.py) is planned
    there."""

    def __init__(self, backing_up: BackingUp) -> None:
        self.backing_up = backing_up
        self.broken = -1   # the tick whose hold breaker's step was deferred

    def new_goal(self) -> None:
        self.broken = -1

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        if not (self.backing_up.stops.hold_breaker_due(now.t) or self.broken == now.number - 1):
            return None
        target = nav.plan_next_step(now.position, now.others)
        nav.committed = target is not None
        self.broken = now.number if nav.step_deferred else -1
        # Not driving on while its step is still being planned: that would drive at what holds the robot, and the
        # guard, stopping it again, would call the hold breaker a second time.
        return drive_on(nav, now, target, not (self.broken == now.number and nav.step_pending_tick == now.number))


class Manoeuvring:
    """A robot that cannot turn in place leaves traps and tight spots by manoeuvres of its own arcs
    (planning/recovery/manoeuvre_driver.py): the manoeuvre under way, until it is over."""

    def __init__(self, model: RobotModel, radius: float, params: PlannerParams, escaping: Escaping,
                 backing_up: BackingUp) -> None:
        self.driver = ManoeuvreDriver(model, radius, params)
        self.escaping, self.backing_up = escaping, backing_up

    def new_goal(self) -> None:
        self.driver.reset()

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        if self.driver.active:
            return self.drive(nav, now.state, now.t, now.dt, now.distance, now.others)
        return None

    def start(self, nav: Steering, world: World, goal: FloatArray, state: FloatArray, t: float,
              others: Sequence[OtherRobot]) -> bool:
        """Search a manoeuvre round the obstacles and parked robots; True if found."""
        parked = parked_world(world, others, goal, nav.radius, nav.params) or world
        if not self.driver.plan(parked, state, goal, t):
            return False
        self.escaping.escape.stop()
        self.backing_up.backup.stop()
        nav.waypoint, nav.committed = None, False
        nav.clear_target()
        nav.progress.made_progress(t)
        nav.mode, nav.reason = Mode.AVOIDING, self.driver.status
        return True

    def drive(self, nav: Steering, state: FloatArray, t: float, dt: float, distance: float,
              others: Sequence[OtherRobot]) -> FloatArray | None:
        """The manoeuvre's command for this tick, guarded; None once it is over (the usual loop takes over)."""
        m = self.driver
        command, ended = m.drive(state, t, distance, lambda c: nav.guard(state, c, dt, others),
                                 lambda: nav.start_manoeuvre(state, t, others))
        if ended:
            nav.trap.reset(t, distance)
            nav.progress.made_progress(t)
        elif command is not None and m.held_since is None:
            nav.mode, nav.reason = Mode.AVOIDING, m.status
        return command
