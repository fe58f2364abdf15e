"""What a navigator does when the guard keeps its robot stopped: the hold breaker, and backing up.

- The hold breaker: two robots the guard holds for each other wait forever if each still sees its own way as
  clear. After HOLD_BEFORE_STEP seconds held for another robot, the held robot plans a step round it.
- A robot counts as stopped until it is HOLD_RELEASE metres from where the guard first stopped it: a command
  the guard lets through (a turn in place, a step of a few centimetres) is not a way out. Counting those as
  moving restarted both timers every other tick, and two differential-drive robots face to face turned and
  twitched for minutes without either backing up (docs/clutter.md, "Differential-drive bases").
- Stuck: stopped HOLD_BEFORE_STEP seconds at a wall, or three times that at a robot (the hold breaker's step
  has had its chance). A robot that cannot turn in place first tries a manoeuvre (planning/manoeuvring.py);
  otherwise, or when none is found, it backs up for BACKUP_TIME seconds (Nav2's backup recovery):
  a holonomic robot straight away from what is nearest; a steered one the move (back or forward, straight or at
  full lock) that gains the most room without folding its trailer. The guard still checks every tick of it,
  and the recovery ends where the guard stops it.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.kinematics.model import RobotModel
from fastep_core.kinematics.tractor_trailer import hitch_angle
from fastep_core.planning.guard import Stop
from fastep_core.planning.others import OtherRobot
from fastep_core.world import World

__all__ = ['BACKUP_SPEED', 'BACKUP_TIME', 'HOLD_BEFORE_STEP', 'HOLD_RELEASE', 'MAX_RECOVERY_HITCH', 'BackUp',
           'StopTimer', 'free_room']

FloatArray = NDArray[np.float64]
HOLD_BEFORE_STEP = 1.0    # seconds a robot waits for another before stepping around it
HOLD_RELEASE = 0.25       # metres from where the guard first stopped it: until then the robot is still stopped
BACKUP_SPEED = 0.25       # m/s of the backing-up recovery ...
BACKUP_TIME = 4.0         # ... for this many seconds (1 m)
MAX_RECOVERY_HITCH = 1.0  # rad: a recovery move may not fold the trailer beyond this (or beyond where it is)


class StopTimer:
    """How long the guard has kept the robot stopped: for another robot (the hold breaker) and at all."""

    def __init__(self) -> None:
        self.held_since: float | None = None    # since when the guard holds the robot for another robot
        self.stuck_since: float | None = None   # since when the guard stops the robot without a break
        self.where: tuple[float, float] | None = None   # where the guard first stopped it

    def moved(self, position: FloatArray) -> None:
        """A command got through: the stop is over once the robot is HOLD_RELEASE from where it began."""
        if self.where is None or math.hypot(position[0] - self.where[0],
                                            position[1] - self.where[1]) >= HOLD_RELEASE:
            self.held_since = self.stuck_since = self.where = None

    def hold_breaker_due(self, t: float) -> bool:
        """Held for another robot HOLD_BEFORE_STEP seconds: time to step round it (the clock restarts)."""
        if self.held_since is not None and t - self.held_since >= HOLD_BEFORE_STEP:
            self.held_since = None
            return True
        return False

    def stopped(self, t: float, stop: Stop | None, position: FloatArray) -> bool:
        """Note a tick the guard stopped; True when the robot is stuck and a recovery is due."""
        if self.where is None:
            self.where = (float(position[0]), float(position[1]))
        if self.held_since is None and stop is Stop.ROBOT:
            self.held_since = t
        if self.stuck_since is None:
            self.stuck_since = t
        patience = HOLD_BEFORE_STEP * (1.0 if stop is Stop.OBSTACLE else 3.0)
        if t - self.stuck_since >= patience:
            self.stuck_since = self.where = None
            return True
        return False


def free_room(world: World, points: FloatArray, others: Sequence[OtherRobot]) -> FloatArray:
    """Free room at points (n, 2): distance to the nearest obstacle surface or other robot's body."""
    room = world.obstacles.clearance(points) if len(world.obstacles) else np.full(len(points), 1e9)
    for other in others:
        room = np.minimum(room, np.hypot(*(points - np.asarray(other.position)).T) - other.radius)
    return room


class BackUp:
    """The backing-up recovery: which move, and until when."""

    def __init__(self, model: RobotModel) -> None:
        self.model = model
        self.until = -math.inf                   # backing up until this time ...
        self.command: FloatArray | None = None   # ... with this command (a steered robot's choice, kept)

    def start(self, t: float) -> None:
        self.until, self.command = t + BACKUP_TIME, None

    def stop(self) -> None:
        self.until = -math.inf

    def active(self, t: float) -> bool:
        return t < self.until

    def drive(self, state: FloatArray, dt: float, room: Callable[[FloatArray], FloatArray],
              guard: Callable[[FloatArray], FloatArray]) -> FloatArray:
        """This tick's command as `guard(command)` lets it through; a refused one ends the recovery."""
        command = self.choose(state, dt, room, lambda option: guard(option) is option)
        guarded = guard(command)
        if guarded is not command:
            self.stop()
        return guarded

    def choose(self, state: FloatArray, dt: float, room: Callable[[FloatArray], FloatArray],
               allowed: Callable[[FloatArray], bool]) -> FloatArray:
        """This tick's command: `room(points)` is the free room at points, `allowed(command)` the guard's verdict."""
        if not self.model.holonomic:
            if self.command is None:
                self.command = self._steered_move(state, dt, room, allowed)
            return self.command
        h = 1e-4
        probes = state[:2] + np.array([[h, 0.0], [-h, 0.0], [0.0, h], [0.0, -h]])
        free = room(probes)
        away = np.array([free[0] - free[1], free[2] - free[3]])
        norm = float(np.hypot(*away))
        return away * (BACKUP_SPEED / norm) if norm > 0 else np.zeros(2)

    def _steered_move(self, state: FloatArray, dt: float, room: Callable[[FloatArray], FloatArray],
                      allowed: Callable[[FloatArray], bool]) -> FloatArray:
        """Of straight back and forward or back at full lock either way, the move that gains the most room over
        the recovery without folding the trailer (hitch angle over MAX_RECOVERY_HITCH) and whose first step
        the guard allows: a wall alongside pins straight moves too, and reversing a trailer far folds it.
        When every move would fold it, straight back (the first option) all the same: cutting moves short
        instead kept trailers straighter but landed fewer robots (docs/robustness.md, "Tractor-trailers before
        manoeuvres")."""
        max_steer = float(getattr(self.model, 'max_steer', 0.0))
        lock = BACKUP_SPEED * math.tan(max_steer) / max(getattr(self.model, 'length', 1.0), 1e-6)
        options = [np.array([v, w]) for v in (-BACKUP_SPEED, BACKUP_SPEED) for w in (0.0, -lock, lock)]
        scores = []
        for option in options:
            if not allowed(option):
                scores.append(-math.inf)
                continue
            probe, folds = state, False
            for _ in range(int(round(BACKUP_TIME / dt))):
                probe = self.model.integrate(probe, option, dt)
                folds = folds or (self.model.trailer and
                                  abs(hitch_angle(probe)) > max(MAX_RECOVERY_HITCH, abs(hitch_angle(state))))
            scores.append(-math.inf if folds else float(room(probe[None, :2])[0]))
        return options[int(np.argmax(scores))]
