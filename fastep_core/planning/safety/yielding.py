"""Yielding to movers: the robot's speed checked against where moving obstacles will be, not where they are.

Movers do not plan and do not give way, and the guard (planning/safety/guard.py) looks one tick ahead, too short to see
one coming. So every tick a mover could come within reach over the next `mover_horizon` seconds, the command is
checked over that horizon (the robot on its model's arc, each mover at its velocity) and the first of these
that keeps `clearance` from every mover wins:

1. the command itself (the same object, so nothing changes where no mover comes near);
2. the command slowed to 3/4, 1/2 or 1/4: *yielding*;
3. standing still: *waiting* for the mover to pass;
4. *getting out of the way*: the move of a fan nearest to the command that keeps clear, else the roomiest.

The guard still checks the choice against still obstacles and robots. Other robots are not movers here: they
plan and give way, and a straight-line prediction of them would be wrong. Used by every navigator; the distance
checks are exact between samples and vectorised over commands, times and movers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.kinematics.model import RobotModel
from fastep_core.planning.others import OtherRobot, OtherRobots

__all__ = ['SAMPLE_TIME', 'SLOWER', 'Yield', 'Yielding', 'predicted_positions', 'closest_approach']

FloatArray = NDArray[np.float64]
SAMPLE_TIME = 0.1              # seconds between predicted positions (distances between them are exact)
SLOWER = (0.75, 0.5, 0.25)     # the command's fractions tried before standing still
HEADINGS = 16                  # a holonomic robot's evasive headings
PREDICTED = (0.5, 1.0)         # a step plans round movers also this far through the time to reach it


@dataclass(frozen=True)
class Yield:
    """What yielding did to one tick's command: `kind` in '', 'yielding', 'waiting', 'evading'."""

    command: FloatArray
    kind: str = ''
    mover: str = ''

    @property
    def reason(self) -> str:
        if self.kind == 'yielding':
            return f'yielding: slowing down for {self.mover}'
        if self.kind == 'waiting':
            return f'waiting for {self.mover} to pass'
        if self.kind == 'evading':
            return f'getting out of the way of {self.mover}'
        return ''


def predicted_positions(model: RobotModel, state: FloatArray, commands: FloatArray,
                        times: FloatArray) -> FloatArray:
    """Where the robot's reference point is at `times` (k,) under each of `commands` (c, 2) held: (c, k, 2).

    A constant command moves each model's reference point along a circle (or a line): its map-frame velocity
    now, turning at the rate one short integration step shows. Exact for the point mass and the differential
    drive; for a tractor-trailer, the tractor's arc (its trailer does not move the reference point).
    """
    commands = np.asarray(commands, dtype=float).reshape(-1, 2)
    position = np.asarray(state[:2], dtype=float)
    velocities = np.array([model.velocity(state, c)[:2] for c in commands]).reshape(-1, 2)
    if model.holonomic or len(state) < 3:
        rates = np.zeros(len(commands))
    else:
        h = 1e-3
        turned = np.array([model.integrate(state, c, h)[2] for c in commands])
        rates = np.angle(np.exp(1j * (turned - float(state[2])))) / h
    t = np.asarray(times, dtype=float)[None, :]
    w = rates[:, None]
    phi = np.arctan2(velocities[:, 1], velocities[:, 0])[:, None]
    speed = np.hypot(velocities[:, 0], velocities[:, 1])[:, None]
    turning = np.abs(w) > 1e-9
    safe_w = np.where(turning, w, 1.0)
    # Arc: integral of speed * (cos, sin)(phi + w s) ds; the straight line where w = 0.
    dx = np.where(turning, speed / safe_w * (np.sin(phi + safe_w * t) - np.sin(phi)), speed * np.cos(phi) * t)
    dy = np.where(turning, speed / safe_w * (np.cos(phi) - np.cos(phi + safe_w * t)), speed * np.sin(phi) * t)
    out: FloatArray = position + np.stack([dx, dy], axis=-1)
    return out


def closest_approach(relative: FloatArray) -> FloatArray:
    """Smallest norm of piecewise-linear relative positions (..., k, 2) over each polyline: (...,)."""
    a, b = relative[..., :-1, :], relative[..., 1:, :]
    d = b - a
    dd = np.einsum('...i,...i->...', d, d)
    s = np.clip(-np.einsum('...i,...i->...', a, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    nearest = a + s[..., None] * d
    smallest: FloatArray = np.hypot(nearest[..., 0], nearest[..., 1]).min(axis=-1)
    return smallest


class Yielding:
    """Checks one robot's commands against the movers over a horizon (see the module docstring)."""

    def __init__(self, model: RobotModel, radius: float, horizon: float, margin: float, max_speed: float,
                 max_turn_rate: float = 0.0) -> None:
        self.model, self.radius, self.horizon, self.margin = model, radius, horizon, margin
        self.max_speed = max_speed if max_speed > 0 else 1.0
        self.max_turn_rate = max_turn_rate if max_turn_rate > 0 else 2.0
        self.times = np.arange(0.0, horizon + 0.5 * SAMPLE_TIME, SAMPLE_TIME) if horizon > 0 else np.zeros(1)

    def relevant(self, state: FloatArray, others: Sequence[OtherRobot]) -> list[OtherRobot]:
        """The movers that could come within reach over the horizon."""
        if self.horizon <= 0:
            return []
        movers = [o for o in others if o.mover] if not isinstance(others, OtherRobots) else others.movers()
        x, y = float(state[0]), float(state[1])
        return [o for o in movers
                if math.hypot(o.position[0] - x, o.position[1] - y) - o.radius - self.radius - self.margin
                < (self.max_speed + math.hypot(*o.velocity)) * self.horizon]

    def check(self, state: FloatArray, command: FloatArray, others: Sequence[OtherRobot],
              allowed: Callable[[FloatArray], bool] = lambda command: True) -> Yield:
        """The command to drive this tick: `command` itself when it keeps clear of every mover (or none is near).

        `allowed(command)`: the guard's verdict on a move out of the way (still obstacles, other robots).
        """
        movers = self.relevant(state, others)
        if not movers:
            return Yield(command)
        centres = np.array([o.position for o in movers], dtype=float)
        velocities = np.array([o.velocity for o in movers], dtype=float)
        reach = np.array([o.radius for o in movers]) + self.radius + self.margin
        paths = centres[:, None, :] + velocities[:, None, :] * self.times[None, :, None]   # (m, k, 2)
        command = np.asarray(command, dtype=float)

        def room(commands: FloatArray) -> FloatArray:
            """Per command, per mover: closest approach minus the reach (c, m); >= 0 keeps clear."""
            robot = predicted_positions(self.model, state, commands, self.times)          # (c, k, 2)
            return closest_approach(robot[:, None, :, :] - paths[None, :, :, :]) - reach[None, :]

        # A mover already within reach (the robot was caught by one): a move is clear if it never gets nearer
        # than that mover is now.
        floor = np.minimum(np.hypot(*(centres - state[:2]).T) - reach, 0.0) - 1e-9
        candidates = np.array([command * f for f in (1.0, *SLOWER, 0.0)])
        margins = room(candidates)
        clear = (margins >= floor[None, :]).all(axis=1)
        worst = movers[int(np.argmin(margins[0]))].name
        if clear[0]:
            return Yield(command)
        if clear[:-1].any():
            return Yield(candidates[int(np.argmax(clear))], 'yielding', worst)
        if clear[-1]:
            return Yield(candidates[-1], 'waiting', worst)
        options = self.evasive_commands(state)
        scores = (room(options) - floor[None, :]).min(axis=1)
        scores[[not allowed(option) for option in options]] = -math.inf
        if (scores >= 0).any():
            # Of the moves that keep clear, the nearest to what the controller wanted (map-frame velocity).
            wanted = self.model.velocity(state, command)[:2]
            change = np.array([math.hypot(*(self.model.velocity(state, o)[:2] - wanted)) for o in options])
            best = int(np.argmin(np.where(scores >= 0, change, math.inf)))
        else:
            best = int(np.argmax(scores))
            if scores[best] <= float((margins[-1] - floor).min()):
                return Yield(candidates[-1], 'waiting', worst)   # nothing does better than standing still
        return Yield(options[best], 'evading', worst)

    def with_predictions(self, position: FloatArray, others: Sequence[OtherRobot], centres: FloatArray,
                         sums: FloatArray, reach_time: float) -> tuple[FloatArray, FloatArray]:
        """A step problem's other centres and radius sums (robot_arrays) with each mover near also where it will
        be halfway through and at the end of the time the robot needs to reach a step (reach_time, at most the
        horizon): the swarm plans its step round the mover's coming track (f2 of eq. 8-9 and the step's
        feasibility), not only round where the mover is now."""
        movers = self.relevant(position, others)
        if not movers:
            return centres, sums
        horizon = min(reach_time, self.horizon)
        where = np.array([o.position for o in movers], dtype=float)
        velocity = np.array([o.velocity for o in movers], dtype=float)
        reach = np.array([o.radius for o in movers], dtype=float) + self.radius
        ahead = np.concatenate([where + velocity * (horizon * f) for f in PREDICTED])
        return np.concatenate([centres, ahead]), np.concatenate([sums, np.tile(reach, len(PREDICTED))])

    def evasive_commands(self, state: FloatArray) -> FloatArray:
        """The fan of moves out of a mover's way: headings at full and half speed, or a steered robot's arcs."""
        v = self.max_speed
        if self.model.holonomic:
            angles = np.linspace(0.0, 2 * math.pi, HEADINGS, endpoint=False)
            unit = np.stack([np.cos(angles), np.sin(angles)], axis=1)
            return np.concatenate([unit * v, unit * 0.5 * v])
        speeds = [v, 0.5 * v] + ([-0.5 * v, -v] if self.model.reverses else [])
        out: list[list[float]] = []
        for s in speeds:
            if self.model.turns_in_place:
                rates = (0.0, 0.5 * self.max_turn_rate, -0.5 * self.max_turn_rate)
            else:   # a steered robot: straight and at full lock either way
                max_steer = float(getattr(self.model, 'max_steer', 0.5))
                lock = abs(s) * math.tan(max_steer) / max(float(getattr(self.model, 'length', 1.0)), 1e-6)
                rates = (0.0, lock, -lock)
            out.extend([s, w] for w in rates)
        return np.array(out, dtype=np.float64)
