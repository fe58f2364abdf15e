"""At the goal: turning to its heading, stopping there (Nav2's stopped goal checker), and backing up to a goal
the robot was carried past."""

from __future__ import annotations

import math

import numpy as np

from fastep_core.planning.behaviours.tick import FloatArray, Steering, Tick
from fastep_core.planning.mode import Mode

__all__ = ['RETURNING', 'RETURN_RANGE', 'ROTATING', 'STOPPING', 'Arrival', 'BackToGoal', 'stopped',
           'turn_to_heading']

ROTATING = 'rotating to the goal heading'
STOPPING = 'stopping at the goal'
RETURNING = 'backing up to the goal it overshot'
RETURN_RANGE = 1.0   # m: a goal overshot by at most this, behind the robot, is backed up to, not turned round for


class Arrival:
    """Within goal_tolerance: turn to the goal's heading, if there is one to turn to; else arrived once stopped
    (the measured speed and turn rate within trans_ and rot_stopped_velocity, Nav2's stopped goal checker), braking
    there until then. A robot carried out of goal_tolerance drives back to the goal (the behaviours after this)."""

    def __init__(self) -> None:
        self.reached = False   # has the robot been within goal_tolerance of this goal

    def new_goal(self) -> None:
        self.reached = False

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        if not now.distance <= nav.params.goal_tolerance:
            return None
        nav.waypoint, nav.cost = None, 0.0
        nav.clear_target()
        self.reached = True
        turn = turn_to_heading(nav, now, now.state, now.dt)
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


class BackToGoal:
    """A goal the robot reached (`arrival`) and was carried past (a base that braked later than planned), now
    behind it within RETURN_RANGE: a robot that turns in place and reverses backs straight up to it, steering to
    keep it astern, at a speed that stops there at the braking the base has shown (within max_reverse_speed),
    instead of turning round (a loop) for a few centimetres. Guarded as every command; in the control loop a laser
    robot backs up only into space its scans saw free (planning/control.py)."""

    def __init__(self, arrival: Arrival) -> None:
        self.arrival = arrival

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        model, p = nav.model, nav.params
        if not self.arrival.reached or now.distance > RETURN_RANGE or model.holonomic or not model.reverses or \
                not model.turns_in_place or model.trailer or len(now.state) < 3:
            return None
        heading = float(now.state[2])
        bearing = math.atan2(float(now.goal[1] - now.position[1]), float(now.goal[0] - now.position[0])) - heading
        astern = math.remainder(bearing - math.pi, math.tau)   # 0 with the goal straight behind
        if abs(astern) >= 0.5 * math.pi:
            return None   # ahead of the robot: the way there is forward
        shown = now.base.braking
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


def turn_to_heading(nav: Steering, now: Tick, state: FloatArray, dt: float) -> FloatArray | None:
    """At the goal's position: the turn in place toward the goal's heading, within the turn rate and its
    acceleration from the last command, and no faster than stops within the heading at the turn braking the base
    has shown (planning/safety/base_response.py); None when there is nothing to turn (no heading, a robot without
    one or that cannot turn in place, params.goal_heading 0, or facing it within yaw_goal_tolerance)."""
    p = nav.params
    heading = now.goal_heading
    if heading is None or not p.goal_heading or nav.model.holonomic or \
            not nav.model.turns_in_place or len(state) < 3:
        return None
    error = math.atan2(math.sin(heading - state[2]), math.cos(heading - state[2]))
    if abs(error) <= p.yaw_goal_tolerance:
        return None
    omega = p.turn_gain * error
    if p.max_turn_rate > 0.0:
        omega = max(-p.max_turn_rate, min(p.max_turn_rate, omega))
    braking = now.base.turn_braking
    if braking > 0.0:
        # Within the yaw tolerance at the end: a turn rate that brakes to a stop over the rest of the error.
        within = math.sqrt(2.0 * braking * max(abs(error) - 0.5 * p.yaw_goal_tolerance, 0.0))
        omega = max(-within, min(within, omega))
    last = now.last_command
    if last is not None and p.max_turn_acceleration > 0.0:
        step = p.max_turn_acceleration * dt
        omega = max(float(last[1]) - step, min(float(last[1]) + step, omega))
    return np.array([0.0, omega])
