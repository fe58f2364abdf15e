"""The base's own controller in front of its motors, like ros2_control's diff_drive_controller.

It takes (v, omega) commands, holds the newest, replaces it by a stop once it is older than `cmd_timeout`, keeps
its own speed and acceleration limits (its speed limiter: those of the BaseDynamics, which may be lower than the
planner believes) and turns the limited twist into the two wheels' speed setpoints (rad/s) for their velocity
servos. It runs at `control_rate`, between whole groups of physics steps (fastep_core/dynamics/plant.py).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from fastep_core.dynamics.params import BaseDynamics

__all__ = ['BaseController']

FloatArray = NDArray[np.float64]


def _toward(current: float, wanted: float, limit: float, step: float) -> float:
    """`wanted` clipped to +-limit, approached from `current` by at most step."""
    wanted = max(-limit, min(limit, wanted))
    return current + max(-step, min(step, wanted - current))


class BaseController:
    """A diff_drive_controller: command in, its timeout and speed limiter, wheel speed setpoints out."""

    def __init__(self, dynamics: BaseDynamics) -> None:
        self.dynamics = dynamics
        self.command = np.zeros(2)          # the newest command taken (v, omega)
        self.command_time: float | None = None   # when it was sent (plant time); None: never
        self.twist = np.zeros(2)            # the limited twist of the last update (v, omega)

    def take(self, command: FloatArray, sent: float) -> None:
        """A command sent at `sent` (plant time, s). Non-finite commands are a stop."""
        v, omega = float(command[0]), float(command[1])
        if not (math.isfinite(v) and math.isfinite(omega)):
            v = omega = 0.0
        self.command = np.array([v, omega])
        self.command_time = sent

    def timed_out(self, t: float) -> bool:
        """Is there no command younger than cmd_timeout at time t?"""
        return self.command_time is None or t - self.command_time > self.dynamics.cmd_timeout

    def update(self, t: float, period: float) -> tuple[float, float]:
        """The wheel speed setpoints (left, right; rad/s) for the next `period` s, from time t."""
        d = self.dynamics
        wanted = (0.0, 0.0) if self.timed_out(t) else (float(self.command[0]), float(self.command[1]))
        v = _toward(float(self.twist[0]), wanted[0], d.max_speed, d.max_acceleration * period)
        omega = _toward(float(self.twist[1]), wanted[1], d.max_angular_speed, d.max_angular_acceleration * period)
        self.twist = np.array([v, omega])
        half = 0.5 * d.wheel_separation * omega
        return (v - half) / d.wheel_radius, (v + half) / d.wheel_radius
