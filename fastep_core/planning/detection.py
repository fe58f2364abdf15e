"""Detection (eq. 11 and "on the way"): does something within sensing range lie on the straight run to a target?

A navigator asks every tick (planning/navigator.py, `blocked`), for the run to its goal or route target and for the
plan_horizon part of it. Other robots are measured every time; obstacles do not move, so an answer about them is
reused while it stays proven (RunDetector.obstacles_on_run says why it holds).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.planning.others import OtherRobot, robots_on_run
from fastep_core.planning.params import PlannerParams
from fastep_core.world import World

__all__ = ['CLEAR_REACH', 'RunDetector']

FloatArray = NDArray[np.float64]
CLEAR_REACH = 1.0   # metres a run proven clear stays proven (obstacles_on_run), at most
ClearRun = tuple[World, tuple[float, float], tuple[float, float], float, float, float, bool]
"""An answer of obstacles_on_run proven: world, start, end, sensing range, `within`, how far the run's ends may
move while it holds, and the answer."""


class RunDetector:
    """One robot's detection, with the answers it may reuse."""

    def __init__(self, radius: float) -> None:
        self.radius = radius
        self._detection: tuple[World, FloatArray, FloatArray, bool] | None = None  # last `blocked` answer
        self._near_detection: tuple[World, FloatArray, FloatArray, bool] | None = None  # ... within plan_horizon
        # A run proven clear of obstacles or blocked by one, and how far its ends may move before it must be
        # measured again (obstacles_on_run): [the run to the target, the plan_horizon run].
        self._clear_runs: list[ClearRun | None] = [None, None]

    def forget(self) -> None:
        """Drop every answer kept (new parameters: sensing range, clearance margin)."""
        self._detection = self._near_detection = None
        self._clear_runs = [None, None]

    def blocked(self, world: World, params: PlannerParams, position: FloatArray, target: FloatArray,
                others: Sequence[OtherRobot], sensing_range: float | None = None, horizon: float | None = None) -> bool:
        """Does something within sensing range lie on the straight run to target? (eq. 11 + 'on the way')

        A run counts as clear if it keeps half the clearance margin beyond the radius: waypoints are placed
        a full margin away, so a robot that just reached one does not see the obstacle it skirts as blocking.
        With a horizon, only the first `horizon` metres of the run count for obstacles (other robots move:
        they count on the whole run).
        """
        rng = params.sensing_range if sensing_range is None else sensing_range
        if robots_on_run(others, self.radius, position, target, rng, 0.5 * params.clearance_margin):
            return True
        # Static obstacles do not move: the answer is reused until the robot has travelled
        # detection_interval, the target changed or the world did (a detector running at a fixed travel rate).
        cached = self._detection if horizon is None else self._near_detection
        if cached is not None and sensing_range is None and cached[0] is world and cached[2] is target and \
                math.hypot(position[0] - cached[1][0], position[1] - cached[1][1]) < params.detection_interval:
            return cached[3]
        within = self.radius + 0.5 * params.clearance_margin
        blocked = False
        if len(world.obstacles):
            end = target
            if horizon is not None:
                length = math.hypot(target[0] - position[0], target[1] - position[1])
                if length > horizon:
                    end = position + (target - position) * (horizon / length)
            blocked = self.obstacles_on_run(world, position, end, rng, within, horizon is not None)
        if sensing_range is None:
            entry = (world, position.copy(), target, blocked)
            if horizon is None:
                self._detection = entry
            else:
                self._near_detection = entry
        return blocked

    def obstacles_on_run(self, world: World, position: FloatArray, end: FloatArray, sensing_range: float,
                         within: float, near_run: bool = False) -> bool:
        """Is an obstacle surface nearer than sensing_range to position and nearer than `within` to the run
        position-end? (`blocked` for the obstacles; `near_run`: the plan_horizon run, which keeps its own proof.)

        The answer is what measuring every obstacle gives, but most measurements are skipped: an answer stays
        proven, without measuring, while the robot and the run's end have moved less than the room it had. Why
        that holds: a surface distance changes by at most the distance the point moved, and a run's distance to
        an obstacle by at most the farther of its two ends' moves. So a clear run stays clear while no obstacle
        not yet within sensing_range + CLEAR_REACH can have come within sensing_range and each of the others
        still keeps more than `within` from the run; a blocked run stays blocked while one obstacle that blocked
        it is still within sensing_range and nearer than `within` to the run. The room is shortened by a
        rounding margin far beyond the floats' own error (1e-6 m, relative to the coordinates' size).
        """
        obstacles = world.obstacles
        slot = 1 if near_run else 0
        proof = self._clear_runs[slot]
        if proof is not None and proof[0] is world and proof[3] == sensing_range and proof[4] == within:
            start, stop = proof[1], proof[2]
            moved = max(math.hypot(position[0] - start[0], position[1] - start[1]),
                        math.hypot(end[0] - stop[0], end[1] - stop[1]))
            if moved < proof[5]:
                return proof[6]
        distance = obstacles.distances(position)
        near = distance < sensing_range
        wide = distance < sensing_range + CLEAR_REACH
        room = CLEAR_REACH
        blocked = False
        if wide.any():
            runs = obstacles.path_distances(position, end)
            blocking = near & (runs < within)
            blocked = bool(near.any() and (runs[near] < within).any())
            if blocked:   # the room of the obstacle that blocks it most surely
                room = float(np.minimum(sensing_range - distance, within - runs)[blocking].max())
            else:
                room = min(room, float(runs[wide].min()) - within)
        scale = max(abs(float(position[0])), abs(float(position[1])), abs(float(end[0])), abs(float(end[1])),
                    obstacles.scale)
        room -= 1e-6 * (1.0 + scale)
        if not math.isfinite(room) or room <= 0.0:
            self._clear_runs[slot] = None
        else:
            self._clear_runs[slot] = (world, (float(position[0]), float(position[1])),
                                      (float(end[0]), float(end[1])), sensing_range, within, room, blocked)
        return blocked
