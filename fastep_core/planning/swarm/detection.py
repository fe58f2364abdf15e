"""Detection (eq. 11 and "on the way"): does something within sensing range lie on the straight run to a target?

A navigator asks every tick (planning/navigator.py, `blocked`), for the run to its goal or route target and for the
plan_horizon part of it. Other robots are measured every time; obstacles do not move, so an answer about them is
reused while it stays proven (RunDetector.obstacles_on_run says why it holds).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.planning.others import OtherRobot, robots_on_run
from fastep_core.planning.params import PlannerParams
from fastep_core.world import World

__all__ = ['RunDetector', 'RunProof']

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class RunProof:
    """An answer of obstacles_on_run and what keeps it proven (RunDetector.obstacles_on_run says why it holds).

    Blocked: while the run's ends have moved less than `room`. Clear: while the new run strays from the old one by
    less than run_room[k], k the number of obstacles the robot may have come within sensing range of (their
    `entry`, ascending, at most how far the robot moved); run_room[k] is the least room of those k obstacles
    (run_room[0] inf: none).
    """

    world: World
    start: tuple[float, float]
    stop: tuple[float, float]
    sensing_range: float
    within: float
    blocked: bool
    room: float = 0.0
    entry: tuple[float, ...] = ()
    run_room: tuple[float, ...] = (math.inf,)

    def holds(self, position: FloatArray, end: FloatArray) -> bool:
        """Is the answer still what measuring would give, for the run position-end?"""
        sx, sy = self.start
        ex, ey = self.stop
        moved = math.hypot(position[0] - sx, position[1] - sy)
        if self.blocked:   # each compared on its own: max() would drop a NaN
            return moved < self.room and math.hypot(end[0] - ex, end[1] - ey) < self.room
        k = bisect.bisect_right(self.entry, moved)   # the obstacles that may have come within sensing range
        if k == 0:
            return True
        room = self.run_room[k]
        return _to_segment(position[0], position[1], sx, sy, ex, ey) < room and \
            _to_segment(end[0], end[1], sx, sy, ex, ey) < room


def _to_segment(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Distance from point p to segment a-b."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 <= 0.0 else min(1.0, max(0.0, ((px - ax) * dx + (py - ay) * dy) / length2))
    return math.hypot(px - ax - t * dx, py - ay - t * dy)


class RunDetector:
    """One robot's detection, with the answers it may reuse."""

    def __init__(self, radius: float) -> None:
        self.radius = radius
        self._detection: tuple[World, FloatArray, FloatArray, bool] | None = None  # last `blocked` answer
        self._near_detection: tuple[World, FloatArray, FloatArray, bool] | None = None  # ... within plan_horizon
        # A run proven clear of obstacles or blocked by one, and what keeps it proven (obstacles_on_run): [the run
        # to the target, the plan_horizon run].
        self._clear_runs: list[RunProof | None] = [None, None]

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
        proven, without measuring, while the robot and the run have moved less than the room it had. Why that
        holds: a surface distance changes by at most the distance the point moved, and the run's distance to an
        obstacle by at most how far the new run strays from the old one, the farther of its two ends' distances
        to the old run (every point of the new run is that close to the old one: the distance to a segment is
        convex along a segment). So
        - a clear run stays clear while every obstacle the robot may have come within sensing_range of (it was
          nearer than sensing_range plus the distance moved) is still farther than `within` from the run. A robot
          driving along its run to a fixed end strays from it by nothing: the answer holds until an obstacle that
          truly lies on the run comes within sensing range (before, every obstacle near the run, wherever, ended
          the proof after the least room of any: a robot skirting one measured again every tick or two);
        - a blocked run stays blocked while one obstacle that blocked it is still within sensing_range and nearer
          than `within` to the run (by the farther of the ends' moves).
        The rooms are shortened by a rounding margin far beyond the floats' own error (1e-6 m, relative to the
        coordinates' size).
        """
        obstacles = world.obstacles
        slot = 1 if near_run else 0
        proof = self._clear_runs[slot]
        if proof is not None and proof.world is world and proof.sensing_range == sensing_range and \
                proof.within == within and proof.holds(position, end):
            return proof.blocked
        distance = obstacles.distances(position)
        near = distance < sensing_range
        start, stop = (float(position[0]), float(position[1])), (float(end[0]), float(end[1]))
        scale = max(abs(start[0]), abs(start[1]), abs(stop[0]), abs(stop[1]), obstacles.scale)
        margin = 1e-6 * (1.0 + scale)
        if not near.any():   # nothing in sensing range: clear until the robot has come within range of one
            nearest = float(distance.min(initial=math.inf)) - sensing_range - margin
            self._clear_runs[slot] = RunProof(world, start, stop, sensing_range, within, False,
                                              entry=(nearest,), run_room=(math.inf, -math.inf)) \
                if math.isfinite(nearest) or not len(distance) else None
            return False
        runs = obstacles.path_distances(position, end)
        blocking = near & (runs < within)
        blocked = bool(blocking.any())
        if blocked:   # the room of the obstacle that blocks it most surely
            room = float(np.minimum(sensing_range - distance, within - runs)[blocking].max()) - margin
            self._clear_runs[slot] = RunProof(world, start, stop, sensing_range, within, True, room=room) \
                if math.isfinite(room) and room > 0.0 else None
            return True
        order = np.argsort(distance, kind='stable')
        entry = distance[order] - sensing_range - margin
        run_room = np.minimum.accumulate(runs[order] - within - margin)
        if not (np.isfinite(entry).all() and np.isfinite(run_room).all()):
            self._clear_runs[slot] = None
            return False
        self._clear_runs[slot] = RunProof(world, start, stop, sensing_range, within, False,
                                          entry=tuple(entry.tolist()), run_room=(math.inf, *run_room.tolist()))
        return False
