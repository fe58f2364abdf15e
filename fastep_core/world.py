"""The static world a robot moves in: a rectangular workspace and its obstacles."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fastep_core.errors import GoalError
from fastep_core.geometry import Obstacle, Obstacles

__all__ = ['World']


@dataclass(frozen=True)
class World:
    """Workspace bounds (xmin, ymin, xmax, ymax) in metres and the obstacles inside them."""

    workspace: tuple[float, float, float, float]
    obstacle_list: tuple[Obstacle, ...] = ()
    obstacles: Obstacles = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, 'obstacles', Obstacles(self.obstacle_list))

    @classmethod
    def from_obstacles(cls, workspace: Sequence[float], obstacles: Sequence[Obstacle]) -> World:
        xmin, ymin, xmax, ymax = (float(v) for v in workspace)
        return cls((xmin, ymin, xmax, ymax), tuple(obstacles))

    def wall_distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """Distance from points to the workspace border (negative outside)."""
        p = np.asarray(points, dtype=float)
        xmin, ymin, xmax, ymax = self.workspace
        return np.minimum(np.minimum(p[..., 0] - xmin, xmax - p[..., 0]),
                          np.minimum(p[..., 1] - ymin, ymax - p[..., 1]))

    def room(self, points: ArrayLike) -> NDArray[np.float64]:
        """Distance from points to the nearest obstacle surface or the workspace border."""
        room = self.wall_distance(points)
        if len(self.obstacles):
            room = np.minimum(room, self.obstacles.clearance(points))
        return room

    def check_point(self, point: Sequence[float], radius: float, what: str = 'goal') -> None:
        """Raise GoalError unless a disc of `radius` at `point` is finite, inside the map and obstacle-free."""
        x, y = float(point[0]), float(point[1])
        if not (math.isfinite(x) and math.isfinite(y)):
            raise GoalError(f'{what} ({point[0]}, {point[1]}) is not finite')
        xmin, ymin, xmax, ymax = self.workspace
        if not (xmin <= x <= xmax and ymin <= y <= ymax):
            raise GoalError(f'{what} ({x:g}, {y:g}) is outside the map [{xmin:g}, {ymin:g}, {xmax:g}, {ymax:g}]')
        clearance = float(self.obstacles.clearance(np.array([x, y])))
        if clearance < 0.0:
            raise GoalError(f'{what} ({x:g}, {y:g}) is occupied: inside an obstacle')
        if clearance < radius:
            raise GoalError(f'{what} ({x:g}, {y:g}) is occupied: {clearance:.3g} m from an obstacle, '
                            f'robot radius {radius:g} m')
