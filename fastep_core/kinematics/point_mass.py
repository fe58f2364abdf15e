"""Point-mass robot and its kinematic controller (eq. 12 of the paper).

The controller dx/dt = alpha1 (x1 - x), dy/dt = alpha2 (y1 - y) drives the robot to the target; Theorem 1 shows
V = |e|^2 / 2 decreases along it. A speed limit scales the velocity vector as a whole, keeping its direction.
Eq. 12 alone converges only exponentially (with Table 1's gain 0.1, 30 s to come within 0.1 m of a goal 2 m away),
so an optional minimum speed m (`min_speed`, the planner's `min_approach_speed`) makes arrival finite: with
u = (alpha1 e_x, alpha2 e_y) and f = min(m, d / dt), u is scaled up to f when 0 < |u| < f, then down to max_speed;
m = 0 is eq. 12 bit for bit. Theorem 1 still holds (dV/dt = -lambda (alpha1 e_x^2 + alpha2 e_y^2) < 0).
Finite time, continuous: with a, A the smaller and larger gain and s = min(m, max_speed), dd/dt <= -(a / A) s, so
arrival within T = (A / a) d0 / s. Discrete (equal gains, alpha dt <= 1, exact integration): each tick moves |u| dt
closer without overshooting, at least s dt unless it ends on the target, so within tol after at most
ceil((d0 - tol) / (s dt)) ticks. tests/fastep_core/kinematics/test_point_mass.py checks both bounds.
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
