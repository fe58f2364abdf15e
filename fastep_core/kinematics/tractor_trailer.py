"""Tractor-trailer robot (eq. 13 of the paper) and its steering controller.

State (x, y, theta0, theta1): the tractor's mid-axle point and the tractor and trailer headings. The model takes
(v, omega), omega = v tan(phi) / L, rather than the paper's steering angle phi, because a Twist carries it and it is
defined at v = 0: x' = v cos(theta0) - (L omega / 2) sin(theta0), y' = v sin(theta0) + (L omega / 2) cos(theta0),
theta0' = omega, theta1' = (v sin(theta0 - theta1) - c omega cos(theta0 - theta1)) / Lt.
Steering law (paper): v = alpha * distance, phi = (7/9) atan(xi + beta / cos|theta0 - theta1|),
beta = max{0, 0.5 - cos|theta1 - theta0|} sign(theta1 - theta0) (anti-jack-knife past 60 degrees; |phi| < 70 deg).
The paper's ODE for xi is garbled; we use the filter xi' = k_xi (K e - xi), xi(0) = K e(0), e the heading error,
stable and turning the tractor toward the target; K = 3, not the paper's 1, which orbits a target closer than the
turning circle forever. Minimum speed (`min_speed`, the planner's min_approach_speed) as for the point mass:
v = max(speed_gain d, min(min_speed, d / dt)), capped at max_speed (0: the paper's law); it changes neither the sign
of v nor phi, so the path's curvature is the law's. No proof of arrival (a target inside the turning circle can be
orbited), so the tests check arrival and that the hitch angle stays far from 90 degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

__all__ = ['TractorTrailer', 'TractorTrailerController', 'hitch_angle', 'wrap_angle']

FloatArray = NDArray[np.float64]
MAX_STEER = 7.0 / 9.0 * math.pi / 2.0  # |phi| < (7/9)(pi/2) = 70 degrees
HEADING_LIMIT = 2.0 ** 16
"""|heading| (rad) beyond which integrate() first normalises theta0 and theta1 into (-pi, pi].

A float heading of 1e15 rad has 0.125 rad steps: the few mrad a step turns were rounded away, the tractor
could not turn and drove off the map. Up to 2^16 rad a float still resolves 1.5e-11 rad, and a run winds up a
few thousand rad at most (2.75 rad/s at full lock for max_sim_time 1500 s), so runs within it are unchanged.
"""


def wrap_angle(a: float) -> float:
    """Angle in (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


def hitch_angle(state: FloatArray) -> float:
    """theta1 - theta0 wrapped to (-pi, pi]: zero when the trailer is straight behind the tractor."""
    return wrap_angle(float(state[3]) - float(state[2]))


@dataclass(frozen=True)
class TractorTrailer:
    """Eq. 13 with input (v, omega). length = L, trailer_length = Lt, hitch_offset = c (metres)."""

    length: float = 1.0
    trailer_length: float = 1.0
    hitch_offset: float = 0.0
    state_size: int = 4
    holonomic: ClassVar[bool] = False        # what it can do (kinematics/model.py)
    turns_in_place: ClassVar[bool] = False   # forward-steered: it turns only while it moves
    reverses: ClassVar[bool] = True
    trailer: ClassVar[bool] = True
    max_steer: ClassVar[float] = MAX_STEER   # steering lock |phi| (rad)

    def derivative(self, state: FloatArray, command: FloatArray) -> FloatArray:
        _, _, th0, th1 = state
        v, omega = command
        lat = 0.5 * self.length * omega
        c0, s0 = math.cos(th0), math.sin(th0)
        rel = th0 - th1
        return np.array([
            v * c0 - lat * s0,
            v * s0 + lat * c0,
            omega,
            (v * math.sin(rel) - self.hitch_offset * omega * math.cos(rel)) / self.trailer_length,
        ])

    def integrate(self, state: FloatArray, command: FloatArray, dt: float) -> FloatArray:
        """One classical Runge-Kutta step with the command held over dt.

        In floats, not 4-element arrays: the guard and the plant integrate every tick, and numpy's per-call
        cost was most of it. Every operation is the one the array form `s + dt / 6 * (k1 + 2 k2 + 2 k3 + k4)`,
        with `k = derivative(s + h k, command)`, does on each element, in the same order: the same floats.
        """
        s = np.asarray(state, dtype=float)
        x, y, th0, th1 = float(s[0]), float(s[1]), float(s[2]), float(s[3])
        if abs(th0) > HEADING_LIMIT or abs(th1) > HEADING_LIMIT:
            th0, th1 = wrap_angle(th0), wrap_angle(th1)
        v, omega = float(command[0]), float(command[1])
        half = 0.5 * dt
        k1 = self._rates(th0, th1, v, omega)
        k2 = self._rates(th0 + half * k1[2], th1 + half * k1[3], v, omega)
        k3 = self._rates(th0 + half * k2[2], th1 + half * k2[3], v, omega)
        k4 = self._rates(th0 + dt * k3[2], th1 + dt * k3[3], v, omega)
        w = dt / 6.0
        return np.array([x + w * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
                         y + w * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
                         th0 + w * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2]),
                         th1 + w * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3])])

    def _rates(self, th0: float, th1: float, v: float, omega: float) -> tuple[float, float, float, float]:
        """derivative() in floats (it depends on the headings and the command only)."""
        lat = 0.5 * self.length * omega
        c0, s0 = math.cos(th0), math.sin(th0)
        rel = th0 - th1
        return (v * c0 - lat * s0, v * s0 + lat * c0, omega,
                (v * math.sin(rel) - self.hitch_offset * omega * math.cos(rel)) / self.trailer_length)

    def velocity(self, state: FloatArray, command: FloatArray) -> FloatArray:
        """Map-frame velocity of the reference point."""
        s = np.asarray(state, dtype=float)
        rates = self._rates(float(s[2]), float(s[3]), float(command[0]), float(command[1]))
        return np.array([rates[0], rates[1]])

    def steering_angle(self, command: FloatArray) -> float:
        """phi recovered from (v, omega); 0 when standing still."""
        v, omega = command
        return math.atan2(omega * self.length, v) if abs(v) > 1e-12 else 0.0


@dataclass
class TractorTrailerController:
    """The paper's steering law with the heading-error filter documented in the module docstring."""

    model: TractorTrailer = field(default_factory=TractorTrailer)
    speed_gain: float = 0.1
    max_speed: float = 0.0
    min_speed: float = 0.0
    xi_rate: float = 2.0
    heading_gain: float = 3.0
    xi: float | None = None

    def reset(self, state: FloatArray, target: FloatArray) -> None:
        self.xi = self.heading_gain * self._heading_error(state, target)

    @staticmethod
    def _heading_error(state: FloatArray, target: FloatArray) -> float:
        bearing = math.atan2(target[1] - state[1], target[0] - state[0])
        return wrap_angle(bearing - float(state[2]))

    def steering(self, state: FloatArray) -> float:
        """phi = (7/9) atan(xi + beta / cos|theta0 - theta1|)."""
        rel = hitch_angle(state)  # theta1 - theta0
        cos_rel = math.cos(abs(rel))
        beta = max(0.0, 0.5 - cos_rel) * math.copysign(1.0, rel) if rel != 0.0 else 0.0
        # cos|rel| can reach 0 only with beta > 0, where the term then saturates atan at +-pi/2.
        push = beta / cos_rel if abs(cos_rel) > 1e-9 else math.copysign(1e9, beta)
        return 7.0 / 9.0 * math.atan((self.xi or 0.0) + push)

    def command(self, state: FloatArray, target: FloatArray, dt: float) -> FloatArray:
        e = self.heading_gain * self._heading_error(state, target)
        if self.xi is None:
            self.xi = e
        else:
            # Exact solution of xi' = k (K e - xi) over dt with e held constant (e here is already K e).
            self.xi = e + (self.xi - e) * math.exp(-self.xi_rate * dt)
        distance = math.hypot(target[0] - state[0], target[1] - state[1])
        v = self.speed_gain * distance
        if self.min_speed > 0.0:
            v = max(v, min(self.min_speed, distance / dt) if dt > 0.0 else self.min_speed)
        if self.max_speed > 0.0:
            v = min(v, self.max_speed)
        phi = self.steering(state)
        return np.array([v, v * math.tan(phi) / self.model.length])


def main() -> None:
    """Drive a tractor-trailer from (5, 5) heading east to (45, 45) and print the hitch angle."""
    model = TractorTrailer()
    ctrl = TractorTrailerController(model, max_speed=1.0)
    state, target = np.array([5.0, 5.0, 0.0, 0.0]), np.array([45.0, 45.0])
    for k in range(1201):
        if k % 150 == 0:
            print(f't={k * 0.05:5.1f}s  x={state[0]:6.2f} y={state[1]:6.2f}  '
                  f'hitch={math.degrees(hitch_angle(state)):6.1f} deg')
        state = model.integrate(state, ctrl.command(state, target, 0.05), 0.05)


if __name__ == '__main__':
    main()
