"""Wheel-encoder odometry: the pose and twist a base reckons from its wheels' turning, as a real one does.

It integrates the *wheel joint angles* (what encoders count), not the body's motion: a wheel that spins on a
slippery floor or slides while braking counts distance the body never drove, so the pose drifts from the truth
(the truth is the physics plant's state). Each reading may carry Gaussian noise (`encoder_noise`, rad) drawn
from a seeded numpy Generator, so the same seed gives the same drift. Pose in the `odom` frame (it starts where
the base starts), twist (v, omega) in the body frame, both from the last two readings, integrated along the
exact arc (as fastep_core/kinematics/diff_drive.py integrates a command).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from fastep_core.kinematics.tractor_trailer import wrap_angle

__all__ = ['WheelOdometry']

FloatArray = NDArray[np.float64]


def _sinc(u: float) -> float:
    return 1.0 - u * u / 6.0 if abs(u) < 1e-4 else math.sin(u) / u


class WheelOdometry:
    """Dead reckoning from two wheel angles (wheel_radius, wheel_separation in metres; noise in rad)."""

    def __init__(self, pose: FloatArray, angles: tuple[float, float], wheel_radius: float, wheel_separation: float,
                 noise: float = 0.0, rng: np.random.Generator | None = None) -> None:
        self.pose = np.array(pose[:3], dtype=float)
        self.twist = np.zeros(2)
        self.wheel_radius = wheel_radius
        self.wheel_separation = wheel_separation
        self.noise = noise
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.last = self._read(angles)

    def _read(self, angles: tuple[float, float]) -> FloatArray:
        reading = np.array(angles, dtype=float)
        if self.noise > 0.0:
            reading = reading + self.noise * self.rng.standard_normal(2)
        return reading

    def update(self, angles: tuple[float, float], dt: float) -> None:
        """A new reading of the wheel angles (left, right; rad), dt seconds after the last one."""
        reading = self._read(angles)
        left, right = ((reading - self.last) * self.wheel_radius).tolist()
        self.last = reading
        distance = 0.5 * (left + right)
        turn = (right - left) / self.wheel_separation
        x, y, theta = self.pose.tolist()
        chord = distance * _sinc(0.5 * turn)
        middle = theta + 0.5 * turn
        self.pose = np.array([x + chord * math.cos(middle), y + chord * math.sin(middle), wrap_angle(theta + turn)])
        self.twist = np.array([distance / dt, turn / dt]) if dt > 0.0 else np.zeros(2)
