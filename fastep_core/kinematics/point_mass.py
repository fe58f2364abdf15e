"""Point-mass robot and its kinematic controller (eq. 12 of the paper).

The controller dx/dt = alpha1 (x1 - x), dy/dt = alpha2 (y1 - y) drives the robot to the target (x1, y1);
Theorem 1 shows V = ((x1 - x)^2 + (y1 - y)^2) / 2 decreases along it. An optional speed limit scales the
velocity vector as a whole, so the direction of motion (and with equal gains, the straight path) is kept and
dV/dt stays negative.

Eq. 12 alone only converges exponentially: the speed is the gain times the distance, so with Table 1's gain
0.1 a robot 2 m from a waypoint starts at 0.2 m/s and needs ln(2 / 0.3) / 0.1 = 19 s to come within 0.3 m
of it, and 30 s to come within 0.1 m of a goal. An optional minimum speed m (`min_speed`, the planner's
`min_approach_speed`) makes the arrival time finite, as follows.

The command. With e = (x1 - x, y1 - y), d = |e| and u = (alpha1 e_x, alpha2 e_y) (eq. 12): when 0 < |u| < f,
with f = min(m, d / dt), u is scaled up to speed f; then, as before, scaled down to max_speed if above it.
So the speed is max(|u|, min(m, d / dt)), capped at max_speed: never above max_speed, never below
min(m, max_speed, d / dt), and the direction is eq. 12's, scaled by a positive factor lambda. m = 0 is eq. 12
exactly (bit for bit: the scaling is skipped).

Theorem 1 still holds: dV/dt = -e . u = -lambda (alpha1 e_x^2 + alpha2 e_y^2) < 0 for e != 0.

Finite time (continuous time). Let a = min(alpha1, alpha2), A = max(alpha1, alpha2) and s = min(m, max_speed)
(s = m when the speed is unlimited). Since e . u >= lambda a d^2 and |u| <= lambda A d,
    dd/dt = -(e . u) / d <= -(a / A) |u| <= -(a / A) s,
so the robot is at the target after at most T = (A / a) d0 / s from distance d0: 10 s for 2 m with equal gains
and m = 0.2 m/s, where eq. 12 alone never gets there.

Finite time (the discrete controller, equal gains alpha, alpha dt <= 1, integrated exactly over each tick as
PointMass.integrate does). u points straight at the target and |u| dt <= d (alpha d dt <= d; min(m, d / dt) dt
<= d), so each tick moves the robot |u| dt closer without overshooting: d' = d - |u| dt. If d <= s dt the
speed is d / dt and the tick ends on the target; otherwise |u| >= s and d drops by at least s dt. The robot is
therefore within a tolerance tol >= 0 of the target after at most ceil((d0 - tol) / (s dt)) ticks, i.e. within
(d0 - tol) / s + dt seconds. tests/fastep_core/kinematics/test_point_mass.py checks both bounds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

__all__ = ['PointMass', 'PointMassController', 'lyapunov']

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class PointMass:
    """A holonomic point: state (x, y), input (vx, vy) in the map frame."""

    state_size: int = 2
    holonomic: ClassVar[bool] = True        # what it can do (kinematics/model.py)
    turns_in_place: ClassVar[bool] = True   # it has no heading to turn
    reverses: ClassVar[bool] = True
    trailer: ClassVar[bool] = False

    def integrate(self, state: FloatArray, command: FloatArray, dt: float) -> FloatArray:
        """Exact zero-order-hold step: the velocity is constant over dt."""
        return state + np.asarray(command, dtype=float) * dt

    def velocity(self, state: FloatArray, command: FloatArray) -> FloatArray:
        """Map-frame velocity of the reference point."""
        return np.asarray(command, dtype=float)


@dataclass
class PointMassController:
    """Eq. 12 with an optional speed limit (max_speed <= 0 means unlimited) and an optional minimum speed
    (min_speed <= 0 means none, the paper's eq. 12): see the module docstring for both and the arrival bound."""

    alpha1: float = 0.1
    alpha2: float = 0.1
    max_speed: float = 0.0
    min_speed: float = 0.0

    def reset(self, state: FloatArray, target: FloatArray) -> None:
        """Stateless: nothing to reset (kept for a uniform controller interface)."""

    def command(self, state: FloatArray, target: FloatArray, dt: float) -> FloatArray:
        u = np.array([self.alpha1 * (target[0] - state[0]), self.alpha2 * (target[1] - state[1])])
        speed = float(np.hypot(u[0], u[1]))
        if self.min_speed > 0.0 and speed > 0.0:
            distance = math.hypot(target[0] - state[0], target[1] - state[1])
            floor = min(self.min_speed, distance / dt) if dt > 0.0 else self.min_speed
            if speed < floor:
                u *= floor / speed
                speed = floor
        if self.max_speed > 0.0 and speed > self.max_speed:
            u *= self.max_speed / speed
        return u


def lyapunov(state: FloatArray, target: FloatArray) -> float:
    """V(x, y) = ((x1 - x)^2 + (y1 - y)^2) / 2 of Theorem 1."""
    return 0.5 * float((target[0] - state[0]) ** 2 + (target[1] - state[1]) ** 2)


def main() -> None:
    """Drive a point mass from (5, 5) to (45, 45) and print V along the way."""
    model, ctrl = PointMass(), PointMassController()
    state, target = np.array([5.0, 5.0]), np.array([45.0, 45.0])
    for k in range(601):
        if k % 100 == 0:
            print(f't={k * 0.1:5.1f}s  x={state[0]:6.2f} y={state[1]:6.2f}  V={lyapunov(state, target):8.3f}')
        state = model.integrate(state, ctrl.command(state, target, 0.1), 0.1)


if __name__ == '__main__':
    main()
