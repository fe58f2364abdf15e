"""Differential-drive base (a unicycle) and its point-to-point controller with a convergence proof.

The model
---------
State (x, y, theta): the midpoint of the wheel axle and the heading; command (v, omega): forward speed and turn
rate in the body frame, what a geometry_msgs/Twist carries as linear.x and angular.z (a TurtleBot-class base):

    x' = v cos(theta),   y' = v sin(theta),   theta' = omega.

`integrate` holds the command over dt (a zero-order hold) and moves the robot exactly along the arc it drives:
with u = omega dt, the chord has length v dt sin(u/2)/(u/2) and the direction theta + u/2, so

    x+ = x + v dt sinc(u/2) cos(theta + u/2),   y+ = y + v dt sinc(u/2) sin(theta + u/2),   theta+ = theta + u,

which is the closed-form solution (no integration error; sinc by its series near 0, so a straight run is exact
too). The heading is returned in (-pi, pi].

Limits, as a real base has them (defaults: PlannerParams max_speed 1 m/s, max_turn_rate 2 rad/s,
max_acceleration 2.5 m/s^2, max_turn_acceleration 3.2 rad/s^2; the accelerations are Nav2's TurtleBot3 DWB
limits, the turn rate a TurtleBot3's 1.8-2.8 rad/s):
- speed |v| <= max_speed and turn rate |omega| <= max_turn_rate: the base saturates each (as ros2_control's
  diff_drive_controller does); the model does the same in `integrate` and `velocity` (0 means unlimited);
- acceleration |dv/dt| <= max_acceleration and |domega/dt| <= max_turn_acceleration: the controller's
  commands respect them (a base cannot change speed at once; its own limiter would only lag the command). The
  guard's stop (planning/guard.py) is an emergency stop and does not wait for them, as Nav2's collision monitor
  stops a robot after the velocity smoother.
It declares (kinematics/model.py): holonomic False (it moves along its heading only), turns_in_place True
(omega with v = 0), reverses True (the base drives backwards: the backing-up recovery uses it; the controller
below drives forward only), trailer False.

The controller
--------------
The polar-coordinate Lyapunov law for the unicycle (Aicardi, Casalino, Bicchi & Balestrino, "Closed loop
steering of unicycle-like vehicles via Lyapunov techniques", IEEE Robotics & Automation Magazine 2(1), 1995;
Siciliano, Sciavicco, Villani & Oriolo, "Robotics: Modelling, Planning and Control", Springer 2009, section
11.6.2, with the final heading left free since a waypoint has none). With rho the distance to the target and
alpha = wrap(atan2(y1 - y, x1 - x) - theta) the heading error, the unicycle obeys

    rho' = -v cos(alpha),   alpha' = -omega + v sin(alpha) / rho.

The law:  v = g cos(alpha),   omega = k2 alpha + g sin(alpha) cos(alpha) / rho,
with k2 = turn_gain > 0 and the approach speed g >= 0
    g = min(max(k1 rho, min(min_speed, rho / dt)), max_speed) * h(alpha),
    h(alpha) = max(0, 1 - |alpha| / drive_within),
k1 = speed_gain (the book's g = k1 rho, h = 1, is the case drive_within = inf, max_speed = 0, min_speed = 0).
h makes the base turn on the spot first and drive once it faces the target within drive_within (0.5 rad by
default), so it leaves the straight run to the target by at most about max_speed drive_within / (2 k2) sideways
(0.125 m with the defaults) where the plain law drifts metres; it also keeps v >= 0 (drive_within < pi/2).
Then, when the command exceeds max_turn_rate, (v, omega) is scaled down by the one factor
s = max(1, |omega| / max_turn_rate): the path's curvature omega / v is unchanged, only the time along it.

Theorem (in the spirit of the paper's Theorem 1). For any start (rho > 0, any heading) the closed loop brings
the base to the target: rho -> 0, and the heading error alpha -> 0 exponentially.
Proof. Substituting the law, with the scale s:
    alpha' = -(k2 alpha + g sin(alpha) cos(alpha) / rho) / s + (g cos(alpha) / s) sin(alpha) / rho = -k2 alpha / s,
so V_alpha = alpha^2 / 2 has V_alpha' = -k2 alpha^2 / s <= -k2 alpha^2 / s_max < 0 for alpha != 0: s is bounded
(|alpha| <= pi, g / rho <= max(k1, 1 / dt)), hence |alpha(t)| <= |alpha(0)| exp(-k2 t / s_max): exponential.
And V = rho^2 / 2 has V' = -rho g cos(alpha)^2 / s <= 0: the distance never grows (the Lyapunov function of
Theorem 1 for the point mass, here for the unicycle). After the finite time T at which |alpha| <= drive_within / 2,
h >= 1/2 and cos(alpha)^2 >= cos(drive_within / 2)^2 > 0, so rho' <= -c min(k1 rho, max_speed) with
c = cos(drive_within / 2)^2 / (2 s_max) > 0: rho decreases at least linearly while k1 rho > max_speed and then
exponentially, rho -> 0. (With min_speed > 0 the floor min(min_speed, rho / dt) only makes g larger: the same
argument, and the base covers the last metres at min_speed instead of slowing down as k1 rho.)
The proof is for continuous time; the controller runs sampled with the exact arc integration of the model, at
k2 dt = 0.1 rad with the defaults, and the floor rho / dt never overshoots the target in one tick. The
acceleration limits act as a rate limiter on top: the command moves from the one last applied toward the law's
at most max_acceleration dt (and max_turn_acceleration dt) per tick, along the straight line between the two in
(v, omega) space (so it stays within the speed and turn limits); once it has caught up it is the law's command.
The tests drive the sampled loop with every limit on from a grid of starts and headings (the target straight
behind included) and check V non-increasing up to the rate limiter's lag and arrival (tests/fastep_core/
kinematics/test_diff_drive.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from fastep_core.kinematics.tractor_trailer import wrap_angle

__all__ = ['DRIVE_WITHIN', 'DiffDrive', 'DiffDriveController', 'heading_error']

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
        wanted = self.law(state, target, dt)
        change = wanted - self.last
        share = 1.0
        if self.max_acceleration > 0.0 and abs(change[0]) > self.max_acceleration * dt:
            share = self.max_acceleration * dt / abs(change[0])
        if self.max_turn_acceleration > 0.0 and abs(change[1]) > self.max_turn_acceleration * dt:
            share = min(share, self.max_turn_acceleration * dt / abs(change[1]))
        return wanted if share >= 1.0 else self.last + share * change


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
