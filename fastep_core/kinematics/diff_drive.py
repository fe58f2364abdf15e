"""Differential-drive base (a unicycle) and its point-to-point controller with a convergence proof.

    python -m fastep_core.kinematics.diff_drive     # drives a base facing away from its target

State (x, y, theta): the wheel axle's midpoint and the heading; command (v, omega): forward speed and turn rate in the
body frame (a Twist's linear.x, angular.z). `integrate` holds the command over dt and moves along the exact arc
(closed form), heading in (-pi, pi]. Limits as a real base has them: |v| <= max_speed and |omega| <= max_turn_rate
saturate (0: unlimited) and the controller's commands keep max_acceleration and max_turn_acceleration; the guard's
stop does not wait for them. Declares: not holonomic, turns in place, reverses (for backing up; the controller drives
forward only), no trailer. Controller: the polar-coordinate Lyapunov law (Aicardi et al. 1995; Siciliano et al. 2009,
11.6.2, final heading free), v = g cos(alpha), omega = k2 alpha + g sin(alpha) cos(alpha) / rho, with a turn-first
factor h(alpha) in g so the base turns on the spot before it drives; commands over max_turn_rate are scaled keeping
the curvature. Theorem: rho -> 0 and alpha -> 0 exponentially from any start. Model, law and proof in full:
docs/architecture.md, "The differential-drive base and its controller" (tests/.../test_diff_drive.py checks it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from fastep_core.kinematics.tractor_trailer import wrap_angle

__all__ = ['DRIVE_WITHIN', 'DiffDrive', 'DiffDriveController', 'heading_error', 'ramp']

FloatArray = NDArray[np.float64]
DRIVE_WITHIN = 0.5
"""rad: the controller drives forward only once the heading error is below this (module docstring, h(alpha))."""


def _sinc(u: float) -> float:
    """sin(u) / u, by its series near 0 (exact to double precision for |u| < 1e-4)."""
    return 1.0 - u * u / 6.0 if abs(u) < 1e-4 else math.sin(u) / u


def _clip(value: float, limit: float) -> float:
    return value if limit <= 0.0 else max(-limit, min(limit, value))


def heading_error(state: FloatArray, target: FloatArray) -> float:
    """alpha = bearing to the target minus the heading, in (-pi, pi]."""
    return wrap_angle(math.atan2(target[1] - state[1], target[0] - state[0]) - float(state[2]))


def ramp(start: FloatArray, wanted: FloatArray, linear: float, turn: float) -> FloatArray:
    """A body-frame command (v, omega) moved from `start` toward `wanted` along one straight line in command space,
    v changing by at most `linear` and omega by at most `turn` (math.inf: no limit): the acceleration limits of one
    command held for one period. The controller and the velocity smoother (planning/safety/smoother.py) both ramp so."""
    change = wanted - start
    share = 1.0
    if abs(change[0]) > linear:
        share = linear / abs(change[0])
    if abs(change[1]) > turn:
        share = min(share, turn / abs(change[1]))
    return wanted if share >= 1.0 else start + share * change


@dataclass(frozen=True)
class DiffDrive:
    """A unicycle: state (x, y, theta), command (v, omega) in the body frame, saturated at the base's limits.

    max_speed (m/s) and max_turn_rate (rad/s) saturate |v| and |omega| (0: unlimited); see the module docstring.
    """

    max_speed: float = 0.0
    max_turn_rate: float = 0.0
    state_size: int = 3
    holonomic: ClassVar[bool] = False       # what it can do (kinematics/model.py): it moves along its heading
    turns_in_place: ClassVar[bool] = True   # omega with v = 0
    reverses: ClassVar[bool] = True
    trailer: ClassVar[bool] = False

    def saturate(self, command: FloatArray) -> tuple[float, float]:
        """(v, omega) as the base executes it: each clipped to its limit."""
        return _clip(float(command[0]), self.max_speed), _clip(float(command[1]), self.max_turn_rate)

    def integrate(self, state: FloatArray, command: FloatArray, dt: float) -> FloatArray:
        """Exact zero-order-hold step along the arc (module docstring); the heading wrapped into (-pi, pi]."""
        x, y, theta = float(state[0]), float(state[1]), float(state[2])
        v, omega = self.saturate(command)
        turn = omega * dt
        chord = v * dt * _sinc(0.5 * turn)
        middle = theta + 0.5 * turn
        return np.array([x + chord * math.cos(middle), y + chord * math.sin(middle), wrap_angle(theta + turn)])

    def velocity(self, state: FloatArray, command: FloatArray) -> FloatArray:
        """Map-frame velocity of the reference point (the axle's midpoint)."""
        v, _ = self.saturate(command)
        theta = float(state[2])
        return np.array([v * math.cos(theta), v * math.sin(theta)])


@dataclass
class DiffDriveController:
    """The polar-coordinate Lyapunov law with speed, turn-rate and acceleration limits (module docstring).

    speed_gain k1 (1/s), turn_gain k2 (1/s); max_speed (m/s), max_turn_rate (rad/s), max_acceleration (m/s^2)
    and max_turn_acceleration (rad/s^2), each 0 for unlimited; min_speed (m/s): the approach speed is at least
    min(min_speed, rho / dt) (0: no floor, the law's k1 rho); drive_within (rad): drive forward only within
    this heading error. `applied` is told the command the robot really got (the navigator calls it every tick,
    a guarded stop included), which is where the next tick's acceleration limit starts from.
    """

    speed_gain: float = 0.1
    turn_gain: float = 2.0
    max_speed: float = 1.0
    max_turn_rate: float = 2.0
    max_acceleration: float = 2.5
    max_turn_acceleration: float = 3.2
    min_speed: float = 0.0
    drive_within: float = DRIVE_WITHIN
    last: FloatArray = field(default_factory=lambda: np.zeros(2))

    def reset(self, state: FloatArray, target: FloatArray) -> None:
        """A new target: the law is memoryless; the base keeps moving as it was (`last` stays)."""

    def applied(self, command: FloatArray) -> None:
        """The command the robot got this tick (the start of the next tick's acceleration window)."""
        self.last = np.array([float(command[0]), float(command[1])])

    def law(self, state: FloatArray, target: FloatArray, dt: float) -> FloatArray:
        """The law's command with the speed and turn-rate limits, before the acceleration limits."""
        rho = math.hypot(target[0] - state[0], target[1] - state[1])
        if rho < 1e-12:
            return np.zeros(2)
        alpha = heading_error(state, target)
        approach = self.speed_gain * rho
        if self.min_speed > 0.0:
            approach = max(approach, min(self.min_speed, rho / dt))
        if self.max_speed > 0.0:
            approach = min(approach, self.max_speed)
        g = approach * max(0.0, 1.0 - abs(alpha) / self.drive_within)
        v = g * math.cos(alpha)
        omega = self.turn_gain * alpha + g * math.sin(alpha) * math.cos(alpha) / rho
        if self.max_turn_rate > 0.0 and abs(omega) > self.max_turn_rate:
            scale = self.max_turn_rate / abs(omega)
            v, omega = v * scale, omega * scale
        return np.array([v, omega])

    def command(self, state: FloatArray, target: FloatArray, dt: float) -> FloatArray:
        """The law's command, moved toward from the last applied one within the acceleration limits."""
        linear = self.max_acceleration * dt if self.max_acceleration > 0.0 else math.inf
        turn = self.max_turn_acceleration * dt if self.max_turn_acceleration > 0.0 else math.inf
        return ramp(self.last, self.law(state, target, dt), linear, turn)


def main() -> None:
    """Drive a base facing away from its target (straight behind it) to the target; print rho and alpha."""
    model = DiffDrive(max_speed=1.0, max_turn_rate=2.0)
    ctrl = DiffDriveController()
    state, target, dt = np.array([5.0, 5.0, math.pi]), np.array([15.0, 5.0]), 0.05
    for k in range(1201):
        if k % 100 == 0:
            rho = math.hypot(target[0] - state[0], target[1] - state[1])
            print(f't={k * dt:5.1f}s  x={state[0]:6.2f} y={state[1]:6.2f} theta={state[2]:6.3f}  '
                  f'rho={rho:7.3f} alpha={heading_error(state, target):6.3f}')
        command = ctrl.command(state, target, dt)
        ctrl.applied(command)
        state = model.integrate(state, command, dt)


if __name__ == '__main__':
    main()
