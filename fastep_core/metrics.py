"""How close robots came to the obstacles and to each other along their trajectories: the one margin function.

fastep-sim, fastep-launch (from odometry) and fastep-report (from a recording) all measure with
trajectory_margins, so their min_clearance numbers mean the same thing: the smallest distance from a robot's
reference point to an obstacle surface, or to a moving circle where it was at that sample time, minus the radii;
against another robot the smallest centre distance minus both radii. Negative means the discs touched (a
collision), inf that there was nothing to measure against.

A robot with a footprint (fastep_core/footprint.py) is judged by its outline instead of its disc against the
obstacles and movers: the polygon placed at each sample's pose (its track then has the heading as a fourth
column), the signed distance from it to an obstacle's surface (negative where they overlap, an obstacle wholly
inside included). Against another robot it stays its circle (its radius: with a footprint, at least the
circumscribed one), conservative.

Robot against robot is compared at the union of both robots' sample times, each position interpolated linearly
between samples and held before the first and after the last. With equal sample times (the in-process simulator,
plants on one simulated clock) this compares exactly the sampled positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fastep_core.footprint import Footprint
from fastep_core.geometry import Obstacles

__all__ = ['Margins', 'MovingCircles', 'barn_score', 'mover_clearance', 'obstacle_clearance', 'positions_at',
           'trajectory_margins']

FloatArray = NDArray[np.float64]
CHUNK = 16_384   # points per obstacles.clearance call: bounds the (points x obstacles) distance matrix


class MovingCircles(Protocol):
    """Circles that move (fastep_core.dynamic_world.Movers): their radii and their centres at any times."""

    radii: FloatArray

    def __len__(self) -> int: ...

    def positions(self, t: ArrayLike) -> FloatArray: ...


@dataclass(frozen=True)
class Margins:
    """Per robot (in the order of the tracks): the smallest margin kept to the obstacles and to the other robots."""

    obstacles: FloatArray
    robots: FloatArray

    @property
    def overall(self) -> FloatArray:
        """The smaller of the two: what a run reports as min_clearance."""
        return np.minimum(self.obstacles, self.robots)


def _rows(track: ArrayLike) -> FloatArray:
    rows = np.asarray(track, dtype=float)
    return rows.reshape(len(rows), -1) if rows.size else np.zeros((0, 3))


def positions_at(track: FloatArray, times: FloatArray) -> FloatArray:
    """Positions (n, 2) of a track (rows t, x, y in time order) at the given times: linearly interpolated
    between samples, held before the first and after the last."""
    return np.stack([np.interp(times, track[:, 0], track[:, 1]), np.interp(times, track[:, 0], track[:, 2])],
                    axis=-1)


def obstacle_clearance(obstacles: Obstacles, points: FloatArray, chunk: int = CHUNK) -> float:
    """Smallest distance from points (n, 2) to the obstacles' surfaces, measured `chunk` points at a time."""
    return float(min(obstacles.clearance(points[k:k + chunk]).min() for k in range(0, len(points), chunk)))


def _closest_approach(a: FloatArray, b: FloatArray) -> float:
    """Smallest centre distance of two non-empty tracks, aligned as the module docstring says."""
    if len(a) == len(b) and np.array_equal(a[:, 0], b[:, 0]):
        pa, pb = a[:, 1:3], b[:, 1:3]
    else:
        times = np.union1d(a[:, 0], b[:, 0])
        pa, pb = positions_at(a, times), positions_at(b, times)
    return float(np.hypot(pa[:, 0] - pb[:, 0], pa[:, 1] - pb[:, 1]).min())


def mover_clearance(movers: MovingCircles, rows: FloatArray, chunk: int = CHUNK) -> float:
    """Smallest distance from a track's points (rows t, x, y) to the movers' centres at the same instants, minus
    the movers' radii, measured `chunk` samples at a time."""
    best = np.inf
    for k in range(0, len(rows), chunk):
        part = rows[k:k + chunk]
        centres = movers.positions(part[:, 0])                       # (n, m, 2)
        gap = np.hypot(centres[..., 0] - part[:, 1, None], centres[..., 1] - part[:, 2, None]) - movers.radii
        best = min(best, float(gap.min()))
    return best


def _footprint_mover_clearance(footprint: Footprint, movers: MovingCircles, rows: FloatArray) -> float:
    """Smallest signed distance from a footprint placed at a track's poses (rows t, x, y, heading) to the movers
    where they are at the same instants (chunked like obstacle_clearance)."""
    best = np.inf
    for k in range(0, len(rows), CHUNK):
        part = rows[k:k + CHUNK]
        best = min(best, float(footprint.circle_distances(part[:, 1:4], movers.positions(part[:, 0]),
                                                          movers.radii).min()))
    return best


def trajectory_margins(tracks: Sequence[ArrayLike], radii: ArrayLike, obstacles: Obstacles,
                       movers: MovingCircles | None = None,
                       footprints: Sequence[Footprint | None] | None = None) -> Margins:
    """The margins of each robot along its track.

    tracks[i]: robot i's samples as rows (t, x, y, ...) in time order (further columns are ignored, but for a
    robot with a footprint the fourth is its heading; a robot may have no samples); radii[i]: its radius.
    movers: moving circles (v2), measured at each of a robot's sample times and counted with the obstacles.
    footprints[i]: robot i's outline, judged against obstacles and movers in place of its disc (None: its disc).
    """
    rows = [_rows(track) for track in tracks]
    radius = np.asarray(radii, dtype=float).reshape(-1)
    if len(radius) != len(rows):
        raise ValueError(f'{len(rows)} tracks but {len(radius)} radii')
    outlines = list(footprints) if footprints is not None else [None] * len(rows)
    if len(outlines) != len(rows):
        raise ValueError(f'{len(rows)} tracks but {len(outlines)} footprints')
    to_obstacles = np.full(len(rows), np.inf)
    to_robots = np.full(len(rows), np.inf)
    for i, mine in enumerate(rows):
        footprint = outlines[i]
        if footprint is not None and len(mine):
            if mine.shape[1] < 4:
                raise ValueError(f'track {i} has a footprint but no heading: rows (t, x, y, heading) needed')
            if len(obstacles):
                to_obstacles[i] = float(footprint.clearance(mine[:, 1:4], obstacles).min())
            if movers is not None and len(movers):
                to_obstacles[i] = min(to_obstacles[i], _footprint_mover_clearance(footprint, movers, mine))
        else:
            if len(mine) and len(obstacles):
                to_obstacles[i] = obstacle_clearance(obstacles, mine[:, 1:3]) - radius[i]
            if len(mine) and movers is not None and len(movers):
                to_obstacles[i] = min(to_obstacles[i], mover_clearance(movers, mine) - radius[i])
        for j in range(i + 1, len(rows)):
            if not len(mine) or not len(rows[j]):
                continue
            gap = _closest_approach(mine, rows[j])
            # Each robot's own radius first: the same rounding as margins computed one robot at a time.
            to_robots[i] = min(to_robots[i], gap - radius[i] - radius[j])
            to_robots[j] = min(to_robots[j], gap - radius[j] - radius[i])
    return Margins(to_obstacles, to_robots)


def barn_score(arrived: bool, collided: bool, traversal_time: float | None, optimal_time: float) -> float:
    """The BARN challenge's score of one run: success x OT / clip(AT, 2 OT, 8 OT), OT the optimal path length over
    the maximum speed, AT the traversal time (s); 0 for a run that did not arrive or collided. At most 0.5."""
    if not arrived or collided or traversal_time is None or not optimal_time > 0.0:
        return 0.0
    return optimal_time / float(np.clip(traversal_time, 2.0 * optimal_time, 8.0 * optimal_time))
