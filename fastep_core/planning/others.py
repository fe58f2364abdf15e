"""Other robots as a planner sees them: moving obstacles with a position, a velocity and a radius."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import point_segment_distance

__all__ = ['OtherRobot', 'robot_arrays', 'robots_on_run']

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class OtherRobot:
    """Another robot as a moving obstacle: where it is, how fast it goes, how big it is."""

    name: str
    position: tuple[float, float]
    velocity: tuple[float, float] = (0.0, 0.0)
    radius: float = 0.5


def robot_arrays(others: Sequence[OtherRobot], radius: float) -> tuple[FloatArray, FloatArray]:
    """The other robots' centres (n, 2) and the sums of their radii and `radius` (n,)."""
    if not others:
        return np.zeros((0, 2)), np.zeros(0)
    centres = np.array([o.position for o in others], dtype=float)
    sums = np.array([o.radius for o in others], dtype=float) + radius
    return centres, sums


def robots_on_run(others: Sequence[OtherRobot], radius: float, start: FloatArray, end: FloatArray,
                  sensing_range: float, margin: float) -> bool:
    """Is another robot within sensing range (surface to surface) and closer to the straight run start-end
    than both radii plus `margin`?"""
    if not others:
        return False
    centres, sums = robot_arrays(others, radius)
    near = np.hypot(*(centres - start).T) - sums < sensing_range
    run = point_segment_distance(centres, start, end)
    return bool(np.any(near & (run < sums + margin)))
