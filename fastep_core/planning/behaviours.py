"""The behaviours of a navigator's control tick, in the order `Navigator.tick` asks them (first answer wins).

Each takes the navigator and the tick (`Tick`) and returns the tick's command (the tick ends there) or None (the
next one is asked): `arrival`, `back_to_goal` (a goal overshot, backed up to), `PathCheck` (a goal nothing reaches
fails), `progress_check`, `trap_check` (starts an escape or a manoeuvre and goes on), `manoeuvre`, `backing_up`,
`HoldBreaker` (a step round a robot the guard holds this one for), `escape` (along the exact path out of a trap) and
`algorithm` (the algorithm's `choose_target`); the last three drive to their target (`drive_on`), guarded in the
navigator's drive_to. Why a list: a reader sees in one place what has priority over what, and each behaviour keeps
its own state. The parts they use: progress.py, escape.py, manoeuvre_driver.py, recovery.py, step_planning.py;
`Steering` is what they need of the navigator (navigator.py), named here so that neither module imports the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.footprint import Footprint
from fastep_core.kinematics.model import Controller, RobotModel
from fastep_core.planning.mode import Mode
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.recovery.back_up import REVERSE_HORIZON, BackUp, SeenFree, StopTimer, free_room, reverse_free
from fastep_core.planning.recovery.escape import ESCAPING, TrapEscape
from fastep_core.planning.recovery.manoeuvre_driver import ManoeuvreDriver
from fastep_core.planning.recovery.progress import ProgressChecker, TrapDetector
from fastep_core.planning.safety.base_response import BaseResponse, ShownResponse
from fastep_core.planning.safety.guard import Guard
from fastep_core.planning.safety.yielding import Yield
from fastep_core.planning.shortest_path.exact_path import parked_world
from fastep_core.planning.shortest_path.optimal import OptimalPath
from fastep_core.planning.swarm.step_planning import StepPlanning
from fastep_core.world import World

__all__ = ['RETURNING', 'RETURN_RANGE', 'ROTATING', 'STOPPING', 'HoldBreaker', 'PathCheck', 'Steering', 'Tick',
           'algorithm', 'arrival', 'back_up', 'back_to_goal', 'backing_up', 'drive_manoeuvre', 'drive_on',
           'escape', 'follow_escape', 'manoeuvre', 'progress_check', 'stand_clear', 'start_escape',
           'start_manoeuvre', 'stopped', 'trap_check', 'trapped', 'turn_to_heading']

FloatArray = NDArray[np.float64]
ROTATING = 'rotating to the goal heading'
STOPPING = 'stopping at the goal'
RETURNING = 'backing up to the goal it overshot'
RETURN_RANGE = 1.0   # m: a goal overshot by at most this, behind the robot, is backed up to, not turned round for


@dataclass(frozen=True)
class Tick:
    """One control tick as the behaviours see it."""

    number: int                    # the navigator's count of ticks
    t: float
    dt: float
    state: FloatArray              # finite
    position: FloatArray           # state[:2]
    others: Sequence[OtherRobot]   # with finite positions
    distance: float                # to the goal
    velocity: FloatArray           # what the base does now, measured (the model's command form), finite


class Steering(Protocol):
    """What the behaviours read and call of a navigator (navigator.py; subclasses override the methods)."""

    goal: FloatArray | None
    goal_heading: float | None
    params: PlannerParams
    model: RobotModel
    controller: Controller
    radius: float
    footprint: Footprint | None
    world: World
    path_world: World
    mode: Mode
    reason: str
    waypoint: FloatArray | None
    cost: float
    reference: OptimalPath | None
    escapes: int
    escapes_traps: bool
    @property
    def seen(self) -> SeenFree | None: ...
    progress: ProgressChecker
    trap: TrapDetector
    escape: TrapEscape
    stops: StopTimer
    backup: BackUp
    manoeuvring: ManoeuvreDriver | None
    guard_check: Guard
    response: BaseResponse

    @property
    def measured_base(self) -> BaseResponse | ShownResponse: ...
    at_goal: bool
    steps: StepPlanning
    yield_kind: str
    _target: FloatArray | None
    _committed: bool

    @property
    def failed(self) -> bool: ...
    @property
    def step_deferred(self) -> bool: ...
    def guard(self, state: FloatArray, command: FloatArray, dt: float,
              others: Sequence[OtherRobot]) -> FloatArray: ...
    def fail(self, reason: str) -> None: ...
    def fail_no_path(self, position: FloatArray) -> None: ...
    def exact_path(self, position: FloatArray, others: Sequence[OtherRobot] = ()) -> OptimalPath | None: ...
    def keep_waypoint(self, position: FloatArray, others: Sequence[OtherRobot]) -> bool: ...
    def start_escape(self, position: FloatArray, distance: float, t: float,
                     others: Sequence[OtherRobot] = ()) -> bool: ...
    def start_manoeuvre(self, state: FloatArray, t: float, others: Sequence[OtherRobot]) -> bool: ...
    def drive_manoeuvre(self, state: FloatArray, t: float, dt: float, distance: float,
                        others: Sequence[OtherRobot]) -> FloatArray | None: ...
    def plan_next_step(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None: ...
    def yield_to_movers(self, state: FloatArray, command: FloatArray, dt: float,
                        others: Sequence[OtherRobot]) -> Yield: ...
    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None: ...
    def drive_to(self, state: FloatArray, target: FloatArray, t: float, dt: float,
                 others: Sequence[OtherRobot]) -> FloatArray: ...


# ------------------------------------------------------------------------------------------- the behaviours
def arrival(nav: Steering, now: Tick) -> FloatArray | None:
    """Within goal_tolerance: turn to the goal's heading, if there is one to turn to; else arrived once stopped
    (the measured speed and turn rate within trans_ and rot_stopped_velocity, Nav2's stopped goal checker), braking
    there until then. A robot carried out of goal_tolerance drives back to the goal (the behaviours after this)."""
    if not now.distance <= nav.params.goal_tolerance:
        return None
    nav.waypoint, nav.cost, nav._target = None, 0.0, None
    nav.at_goal = True
    turn = turn_to_heading(nav, now.state, now.dt)
    if turn is None:
        if not stopped(nav, now.velocity):
            nav.mode, nav.reason = Mode.KINEMATIC, STOPPING
            nav.progress.made_progress(now.t)
            return np.zeros(2)
        nav.mode, nav.reason = Mode.ARRIVED, 'goal reached'
        return np.zeros(2)
    nav.mode, nav.reason = Mode.KINEMATIC, ROTATING
    nav.progress.made_progress(now.t)
    return nav.guard(now.state, turn, now.dt, now.others)


class PathCheck:
    """On the goal's first tick: its exact path (the navigator's `reference`); a goal nothing reaches fails."""

    def __init__(self) -> None:
        self.checked = False   # has the goal been checked for a path

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        if self.checked:
            return None
        self.checked = True
        nav.reference = nav.exact_path(now.position)
        if nav.reference is None:
            nav.fail_no_path(now.position)
            return np.zeros(2)
        return None


def progress_check(nav: Steering, now: Tick) -> FloatArray | None:
    """No progress for progress_timeout: the goal fails (progress.py)."""
    if nav.progress.stalled(now.t, now.distance):
        nav.fail(nav.progress.reason)
        return np.zeros(2)
    return None


def trap_check(nav: Steering, now: Tick) -> FloatArray | None:
    """Trapped: a robot that cannot turn in place manoeuvres out if it can, any other escapes along the exact path;
    the tick goes on with it (a stop only when there is no way out)."""
    if trapped(nav, now.t, now.distance):
        if nav.manoeuvring is not None and nav.start_manoeuvre(now.state, now.t, now.others):
            nav.escapes += 1
        elif not nav.start_escape(now.position, now.distance, now.t, now.others):
            return np.zeros(2)
    return None


def manoeuvre(nav: Steering, now: Tick) -> FloatArray | None:
    """The manoeuvre under way (manoeuvre_driver.py), until it is over."""
    if nav.manoeuvring is not None and nav.manoeuvring.active:
        return nav.drive_manoeuvre(now.state, now.t, now.dt, now.distance, now.others)
    return None


def backing_up(nav: Steering, now: Tick) -> FloatArray | None:
    """The backing-up recovery under way (recovery.py)."""
    return back_up(nav, now.state, now.dt, now.others) if nav.backup.active(now.t) else None


class HoldBreaker:
    """Held by the guard for another robot a while (recovery.py, StopTimer): one step round it, driven to its end
    (the navigator's `_committed`); a step deferred to the next tick (step_planning.py) is planned there."""

    def __init__(self) -> None:
        self.broken = -1   # the tick whose hold breaker's step was deferred

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        if not (nav.stops.hold_breaker_due(now.t) or self.broken == now.number - 1):
            return None
        target = nav.plan_next_step(now.position, now.others)
        nav._committed = target is not None
        self.broken = now.number if nav.step_deferred else -1
        # Not driving on while its step is still being planned: that would drive at what holds the robot, and the
        # guard, stopping it again, would call the hold breaker a second time.
        return drive_on(nav, now, target, not (self.broken == now.number and nav.steps.pending_tick == now.number))


def escape(nav: Steering, now: Tick) -> FloatArray | None:
    """Along the exact path out of a trap (escape.py), until the robot has left it; no path left: failed."""
    target = follow_escape(nav, now.position, now.distance, now.t, now.others) if nav.escape.active else None
    if nav.failed:
        return np.zeros(2)
    return drive_on(nav, now, target) if nav.escape.active else None


def algorithm(nav: Steering, now: Tick) -> FloatArray:
    """The algorithm's target (`choose_target`)."""
    return drive_on(nav, now, nav.choose_target(now.position, now.others))


def drive_on(nav: Steering, now: Tick, target: FloatArray | None, drive_on_deferred: bool = True) -> FloatArray:
    """Drive to target; without one, while the step is deferred to the next tick, on to the last target as before
    (rather than stopping for one tick in the middle of a crowd), else stop."""
    if target is None:
        if nav.step_deferred and nav._target is not None and drive_on_deferred:
            return nav.drive_to(now.state, nav._target, now.t, now.dt, now.others)
        nav._target = None
        return np.zeros(2)
    return nav.drive_to(now.state, target, now.t, now.dt, now.others)


# ---------------------------------------------------------------------------------------- what they use
def back_to_goal(nav: Steering, now: Tick) -> FloatArray | None:
    """A goal the robot reached and was carried past (a base that braked later than planned), now behind it within
    RETURN_RANGE: a robot that turns in place and reverses backs straight up to it, steering to keep it astern, at a
    speed that stops there at the braking the base has shown (within max_reverse_speed), instead of turning round
    (a loop) for a few centimetres. Guarded as every command; in the control loop a laser robot backs up only into
    space its scans saw free (control.py)."""
    model, p = nav.model, nav.params
    if not nav.at_goal or now.distance > RETURN_RANGE or model.holonomic or not model.reverses or \
            not model.turns_in_place or model.trailer or len(now.state) < 3 or nav.goal is None:
        return None
    heading = float(now.state[2])
    bearing = math.atan2(float(nav.goal[1] - now.position[1]), float(nav.goal[0] - now.position[0])) - heading
    astern = math.remainder(bearing - math.pi, math.tau)   # 0 with the goal straight behind
    if abs(astern) >= 0.5 * math.pi:
        return None   # ahead of the robot: the way there is forward
    shown = nav.measured_base.braking
    braking = shown if shown > 0.0 else math.inf
    speed = min(math.sqrt(2.0 * braking * max(now.distance - 0.5 * p.goal_tolerance, 0.0)),
                now.distance / now.dt)
    if p.max_reverse_speed > 0.0:
        speed = min(speed, p.max_reverse_speed)
    omega = p.turn_gain * astern
    if p.max_turn_rate > 0.0:
        omega = max(-p.max_turn_rate, min(p.max_turn_rate, omega))
    nav.mode, nav.reason = Mode.KINEMATIC, RETURNING
    nav.progress.made_progress(now.t)
    return nav.guard(now.state, np.array([-speed * max(math.cos(astern), 0.0), omega]), now.dt, now.others)


def stopped(nav: Steering, velocity: FloatArray) -> bool:
    """Is the robot standing, as measured (trans_stopped_velocity, rot_stopped_velocity)?"""
    p = nav.params
    if nav.model.holonomic:
        return math.hypot(float(velocity[0]), float(velocity[1])) <= p.trans_stopped_velocity
    return abs(float(velocity[0])) <= p.trans_stopped_velocity and abs(float(velocity[1])) <= p.rot_stopped_velocity


def turn_to_heading(nav: Steering, state: FloatArray, dt: float) -> FloatArray | None:
    """At the goal's position: the turn in place toward the goal's heading, within the turn rate and its
    acceleration from the last command, and no faster than stops within the heading at the turn braking the base
    has shown (planning/safety/base_response.py); None when there is nothing to turn (no heading, a robot without one
    or that cannot turn in place, params.goal_heading 0, or facing it within yaw_goal_tolerance)."""
    p = nav.params
    if nav.goal_heading is None or not p.goal_heading or nav.model.holonomic or \
            not nav.model.turns_in_place or len(state) < 3:
        return None
    error = math.atan2(math.sin(nav.goal_heading - state[2]), math.cos(nav.goal_heading - state[2]))
    if abs(error) <= p.yaw_goal_tolerance:
        return None
    omega = p.turn_gain * error
    if p.max_turn_rate > 0.0:
        omega = max(-p.max_turn_rate, min(p.max_turn_rate, omega))
    braking = nav.measured_base.turn_braking
    if braking > 0.0:
        # Within the yaw tolerance at the end: a turn rate that brakes to a stop over the rest of the error.
        within = math.sqrt(2.0 * braking * max(abs(error) - 0.5 * p.yaw_goal_tolerance, 0.0))
        omega = max(-within, min(within, omega))
    last = getattr(nav.controller, 'last', None)
    if last is not None and p.max_turn_acceleration > 0.0:
        step = p.max_turn_acceleration * dt
        omega = max(float(last[1]) - step, min(float(last[1]) + step, omega))
    return np.array([0.0, omega])


def trapped(nav: Steering, t: float, distance: float) -> bool:
    """Has the robot failed to come closer to the goal for trap_timeout seconds (outside an escape)?"""
    if not nav.escapes_traps or nav.escape.active or (nav.manoeuvring is not None and nav.manoeuvring.active):
        return False
    return nav.trap.trapped(t, distance)


def start_escape(nav: Steering, position: FloatArray, distance: float, t: float,
                 others: Sequence[OtherRobot] = ()) -> bool:
    """Leave a trap along the exact shortest path (escape.py); False (and failed) if there is none."""
    assert nav.goal is not None
    path = nav.exact_path(position, others)
    if path is None:
        nav.fail_no_path(position)
        return False
    nav.escapes += 1
    nav.escape.start(path, nav.path_world, t, min(distance, nav.trap.best) - nav.params.progress_distance, nav.world)
    nav.waypoint, nav._committed = None, False
    nav.progress.made_progress(t)
    nav.mode, nav.reason = Mode.AVOIDING, ESCAPING
    return True


def follow_escape(nav: Steering, position: FloatArray, distance: float, t: float,
                  others: Sequence[OtherRobot]) -> FloatArray | None:
    """The escape's target; None once the robot has left the trap, or failed with no path left.

    A step around another robot (the hold breaker) leaves the path, which is planned again after it; so does a
    change of the world the robot knows (a sensed obstacle) that brings an obstacle within radius + a quarter
    margin of the rest of the path (the path was planned round what the robot knew then).
    """
    assert nav.goal is not None
    if nav.escape.left(distance):
        nav.trap.reset(t, distance)
        return None
    replan = nav._committed
    path = nav.escape.path
    assert path is not None   # escaping
    if nav.escape.known is not nav.world:
        parked = parked_world(nav.world, others, nav.goal, nav.radius, nav.params) or nav.world
        keep = min(path.keep, nav.radius + 0.25 * nav.params.clearance_margin) - 1e-6
        replan = not nav.escape.adopt(nav.world, parked, keep) or replan
    if nav._committed:
        if nav.keep_waypoint(position, others):
            return nav.waypoint
        nav._committed = False

    def plan() -> tuple[OptimalPath, World] | None:
        path = nav.exact_path(position, others)
        return None if path is None else (path, nav.path_world)

    target, progressed = nav.escape.next_target(position, t, plan, nav.radius, nav.params, replan, nav.world)
    if target is None:
        nav.fail_no_path(position)
        return None
    if progressed:
        nav.progress.made_progress(t)
    nav.mode, nav.reason = Mode.AVOIDING, ESCAPING
    return target


def back_up(nav: Steering, state: FloatArray, dt: float, others: Sequence[OtherRobot]) -> FloatArray:
    """The backing-up recovery's command (recovery.py), guarded; it ends where the guard stops it."""
    seen = nav.seen
    free = None if seen is None else (
        lambda command: reverse_free(nav.model, state, nav.radius, command, REVERSE_HORIZON, nav.world, seen,
                                     (), nav.guard_check.obstacle_margin, nav.footprint))
    guarded = nav.backup.drive(state, dt, lambda points: free_room(nav.world, points, others),
                               lambda command: nav.guard(state, command, dt, others), free)
    if nav.backup.looking:
        nav.reason = 'backing up: stuck; turning to see the space behind (no scan has seen it free)'
    elif nav.backup.until > -math.inf:
        nav.reason = 'backing up: stuck'
    return guarded


def start_manoeuvre(nav: Steering, state: FloatArray, t: float, others: Sequence[OtherRobot]) -> bool:
    """Search a manoeuvre (manoeuvre_driver.py) round the obstacles and parked robots; True if found."""
    assert nav.goal is not None and nav.manoeuvring is not None
    world = parked_world(nav.world, others, nav.goal, nav.radius, nav.params) or nav.world
    if not nav.manoeuvring.plan(world, state, nav.goal, t):
        return False
    nav.escape.stop()
    nav.backup.stop()
    nav.waypoint, nav._committed, nav._target = None, False, None
    nav.progress.made_progress(t)
    nav.mode, nav.reason = Mode.AVOIDING, nav.manoeuvring.status
    return True


def drive_manoeuvre(nav: Steering, state: FloatArray, t: float, dt: float, distance: float,
                    others: Sequence[OtherRobot]) -> FloatArray | None:
    """The manoeuvre's command for this tick, guarded; None once it is over (the usual loop takes over)."""
    m = nav.manoeuvring
    assert m is not None
    command, ended = m.drive(state, t, distance, lambda c: nav.guard(state, c, dt, others),
                             lambda: nav.start_manoeuvre(state, t, others))
    if ended:
        nav.trap.reset(t, distance)
        nav.progress.made_progress(t)
    elif command is not None and m.held_since is None:
        nav.mode, nav.reason = Mode.AVOIDING, m.status
    return command


def stand_clear(nav: Steering, state: FloatArray, others: Sequence[OtherRobot]) -> FloatArray:
    """A robot standing still (no valid step, held, waiting) that a mover would run into gets out of its
    way (yielding.py); zeros otherwise."""
    stop = np.zeros(2)
    state = np.asarray(state, dtype=float)
    if not np.isfinite(state).all():
        return stop
    yielded = nav.yield_to_movers(state, stop, nav.params.dt, others)
    if yielded.kind != 'evading':
        return stop
    nav.yield_kind, nav.reason = yielded.kind, yielded.reason
    return yielded.command
