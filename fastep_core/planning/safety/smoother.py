"""The velocity smoother: the last stage between a command and cmd_vel, for every robot model.

Whatever chose a command (a controller, DWA, a recovery, yielding), the base gets it as Nav2's velocity_smoother
(nav2_velocity_smoother, the anchor) would send it. First the speed limits, one factor for all components so a
steered robot keeps its path's curvature: |v| <= max_speed, v >= -max_reverse_speed, |omega| <= max_turn_rate
where the model has one (diff_drive; commands (v, omega), body frame); a point mass's (vx, vy) (map frame) has
its norm capped at max_speed and no rear, so no reverse cap. Then the acceleration limits: the command moves from
the velocity the base has toward the capped one by at most max_acceleration (a point mass: the norm of the change)
and max_turn_acceleration times the time it is held, along one straight line in command space (Nav2's
scale_velocities). That time is the time since the last command, capped at one control tick (`period`): after a
pause of any length the base ramps from what it is doing (the last command sent, or odometry's twist given to
`reset`), never jumps. A limit lowered below the current speed is reached braking at max_acceleration, as Nav2
does. Only the guard's emergency stop (`emergency=True`) brakes harder, at emergency_deceleration (its turn
braking scaled alike). 0 for any limit means unlimited; a command that is not finite is a stop.

Closed loop (Nav2's CLOSED_LOOP feedback): `feedback` gives it the velocity odometry measured. While that lies
within FEEDBACK_BOUND of the last command, or is exactly one of the last FEEDBACK_COMMANDS (odometry a command or
two behind on a graph; planning/safety/base_response.py), the base does what it is told and the ramp goes on from the
last command;
otherwise (a heavy base coasting faster than its command, a base behind a ramp it cannot follow) the ramp starts
from the measured velocity. A base that does exactly what it is told never moves the ramp off its commands.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fastep_core.kinematics.diff_drive import ramp
from fastep_core.kinematics.model import RobotModel
from fastep_core.planning.limits import Limits
from fastep_core.planning.safety.base_response import FEEDBACK_COMMANDS, all_finite, off_commands

__all__ = ['VelocitySmoother']

FloatArray = NDArray[np.float64]


def _zeros() -> FloatArray:
    return np.zeros(2)


@dataclass
class VelocitySmoother:
    """Speed and acceleration limits on every command of one robot (module docstring).

    holonomic: commands are map-frame (vx, vy) (a point mass), else body-frame (v, omega). turn_limited: the
    model has a turn-rate limit (diff_drive). `limits` are the navigator's (`for_model`, `retune`), read as they
    are: a point mass has no reverse or turn limits, only a turn-limited model a turn rate. `period` is the control
    tick (limits.dt, then each command's: the control loop sets it), the most time one command's change is spread
    over. `velocity` is what the base does now.
    """

    holonomic: bool
    turn_limited: bool = False
    limits: Limits = field(default_factory=Limits)
    period: float = 0.05
    velocity: FloatArray = field(default_factory=_zeros)
    sent: deque[FloatArray] = field(default_factory=lambda: deque(maxlen=FEEDBACK_COMMANDS))

    @classmethod
    def for_model(cls, model: RobotModel, limits: Limits) -> VelocitySmoother:
        """The smoother of a robot of this model (make_robot's), with these limits (PlannerParams.limits)."""
        smoother = cls(bool(model.holonomic), turn_limited=hasattr(model, 'max_turn_rate'))
        smoother.retune(limits)
        return smoother

    def retune(self, limits: Limits) -> None:
        """New limits, from the next command on; the base's velocity is kept (it ramps to the new limits)."""
        self.limits = limits
        self.period = limits.dt

    @property
    def max_speed(self) -> float:
        return self.limits.max_speed

    @property
    def max_reverse_speed(self) -> float:
        """The reverse cap: a point mass has no rear, so none."""
        return 0.0 if self.holonomic else self.limits.max_reverse_speed

    @property
    def max_turn_rate(self) -> float:
        """The turn-rate cap of a turn-limited model (diff_drive), none for the others."""
        return self.limits.max_turn_rate if self.turn_limited and not self.holonomic else 0.0

    @property
    def max_acceleration(self) -> float:
        return self.limits.max_acceleration

    @property
    def max_turn_acceleration(self) -> float:
        """A point mass ramps the norm of its velocity change (max_acceleration), no turn."""
        return 0.0 if self.holonomic else self.limits.max_turn_acceleration

    @property
    def emergency_deceleration(self) -> float:
        return self.limits.emergency_deceleration

    def reset(self, velocity: ArrayLike) -> None:
        """What the base is doing now, in the model's command form (odometry's twist after a pause, say); the next
        command ramps from it. Not finite: standing still."""
        v = np.asarray(velocity, dtype=float).reshape(2)
        self.velocity = v.copy() if np.isfinite(v).all() else np.zeros(2)
        self.sent.clear()

    def take_back(self, velocity: FloatArray) -> None:
        """The last smoothed command was not sent: the base's velocity is `velocity` again."""
        if self.sent:
            self.sent.pop()
        self.velocity = velocity

    def feedback(self, measured: ArrayLike | None) -> bool:
        """The velocity odometry measured (None: not known): the ramp starts from it when the base is not doing what
        the recent commands asked (module docstring). True if it does now."""
        if measured is None:
            return False
        m = np.asarray(measured, dtype=float).reshape(2)
        if not all_finite(m):
            return False
        if not off_commands(m, self.sent or (self.velocity,), self.holonomic):
            return False
        self.velocity = m.copy()
        self.sent.clear()
        return True

    def cap(self, command: ArrayLike) -> FloatArray:
        """The command within the speed limits, scaled down by one factor (the direction or curvature stays)."""
        c = np.asarray(command, dtype=float).reshape(2)
        if not all_finite(c):
            return np.zeros(2)
        over = 1.0
        if self.holonomic:
            speed = math.hypot(c[0], c[1])
            if self.max_speed > 0.0 and speed > self.max_speed:
                over = speed / self.max_speed
        else:
            v, omega = float(c[0]), float(c[1])
            if self.max_speed > 0.0 and v > self.max_speed:
                over = v / self.max_speed
            if self.max_reverse_speed > 0.0 and -v > self.max_reverse_speed:
                over = max(over, -v / self.max_reverse_speed)
            if self.max_turn_rate > 0.0 and abs(omega) > self.max_turn_rate:
                over = max(over, abs(omega) / self.max_turn_rate)
        capped: FloatArray = c / over if over > 1.0 else c
        return capped

    def accelerations(self, emergency: bool = False) -> tuple[float, float]:
        """(linear, turn) acceleration limits of a command, math.inf for unlimited; the emergency stop's at
        emergency_deceleration, its turn braking scaled by emergency_deceleration / max_acceleration."""
        linear = self.max_acceleration if self.max_acceleration > 0.0 else math.inf
        turn = self.max_turn_acceleration if self.max_turn_acceleration > 0.0 else math.inf
        if emergency:
            harder = self.emergency_deceleration / linear if self.emergency_deceleration > 0.0 else math.inf
            scale = max(harder, 1.0)   # never gentler than any other command
            linear, turn = linear * scale, turn * scale
        return linear, turn

    def smooth(self, command: ArrayLike, elapsed: float, emergency: bool = False) -> FloatArray:
        """The command to send: `command` capped, reached from the base's velocity within the acceleration limits
        over min(elapsed, period) seconds (elapsed: since the last command). emergency: it is the guard's stop."""
        wanted = self.cap(command)
        window = min(elapsed, self.period) if elapsed > 0.0 else 0.0   # NaN and negative: no time, no change
        linear, turn = self.accelerations(emergency)
        if self.holonomic:
            change = wanted - self.velocity
            size = math.hypot(change[0], change[1])
            share = linear * window / size if size > linear * window else 1.0
            sent = wanted if share >= 1.0 else self.velocity + share * change
        else:
            sent = ramp(self.velocity, wanted, linear * window, turn * window)
        self.velocity = sent.copy()
        self.sent.append(self.velocity)
        return sent
