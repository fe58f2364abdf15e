"""Fusion of a scan with what the robot already believes: the points a believed surface explains, and the
believed obstacles the scan sees through.

- Explained points: a point within EXPLAINED of a believed obstacle's surface, or inside it, is that obstacle
  (the map's, possibly misplaced; one perception added); a point within EXPLAINED of another robot's circle
  (its odometry) or of a known mover's reported circle is that robot or mover. Only the rest can be new.
- Seen through: a believed obstacle is contradicted by a beam that reads farther than the obstacle's surface
  on that beam by more than SEE_THROUGH (the beam passed where the obstacle should be). Only obstacles whose
  surface the beam would reach within range_max - SEE_THROUGH count (beyond, the beam says nothing), and the
  obstacle is shrunk by SEE_THROUGH first (circles' radii, segments' ends: grazing beams say nothing); a beam
  with no reading (NaN: a dark or glass surface, an error) says nothing either, +inf (no return within range)
  that its whole length is free. An
  obstacle contradicted by at least SEE_THROUGH_BEAMS beams of one scan is not where the map says (a misplaced
  obstacle's ghost, or a mover perception once took for a still obstacle). Vectorised: each obstacle against
  the beams that can meet it (laser.fan_hits, the same distances as all beams x all obstacles).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Obstacles
from fastep_core.sensing.laser import Scan, fan_hits

__all__ = ['END_SLACK', 'EXPLAINED', 'SEE_THROUGH', 'SEE_THROUGH_BEAMS', 'explained', 'seen_through']

FloatArray = NDArray[np.float64]

END_SLACK = 0.03
"""Metres beyond a believed wall's end within which a scan point is still that wall (the range noise along a
grazing beam): farther out it is not, though within EXPLAINED of the end. A misplaced wall that stops short of the
true one hid the true end's points, and FAStep-Route clipped the true end rounding the ghost's
(misplaced_obstacles:1000025, 17.8 mm, docs/dynamic_world.md)."""
EXPLAINED = 0.12
"""Metres from a believed surface within which a scan point is that surface: the noise (1 cm, 3 sigma), a fit's
error, a polyline's tolerance (0.1 m). No more: a misplaced obstacle's surface would hide the true one's points
within this distance, and the robot would pass the truth as closely as the ghost (0.25 m did: shallow
collisions in the misplaced family, docs/dynamic_world.md)."""
SEE_THROUGH = 0.3
"""Metres a reading must exceed a believed surface on its beam to contradict it."""
SEE_THROUGH_BEAMS = 3
"""Beams of one scan that must see through an obstacle before it is dropped."""


def explained(points: FloatArray, obstacles: Obstacles, centres: FloatArray, radii: FloatArray,
              tolerance: float = EXPLAINED, map_obstacles: Obstacles | None = None) -> NDArray[np.bool_]:
    """Which points (n, 2) a believed obstacle or a circle (centres (k, 2), radii (k,): other robots, known
    movers) explains. `map_obstacles`: believed obstacles that come from the map, whose walls explain no point
    beyond their ends (END_SLACK): a map may misplace a wall, a scan's own walls end where the points did."""
    out = np.zeros(len(points), dtype=bool)
    if not len(points):
        return out
    if len(obstacles):
        out |= obstacles.near(points, tolerance)
    if map_obstacles is not None and len(map_obstacles):
        out |= map_obstacles.near(points, tolerance, END_SLACK)
    if len(centres):
        gap = np.hypot(points[:, None, 0] - centres[:, 0], points[:, None, 1] - centres[:, 1]) - radii
        out |= (gap < tolerance).any(axis=1)
    return out


def seen_through(scan: Scan, pose: FloatArray, obstacles: Obstacles, through: float = SEE_THROUGH) -> NDArray[np.bool_]:
    """Which believed obstacles (circles first, as Obstacles orders them) this scan from pose sees through;
    `through`: SEE_THROUGH (module docstring), or less for a shape fitted to this very scan, whose surface is
    known to the noise."""
    out = np.zeros(len(obstacles), dtype=bool)
    if not len(obstacles):
        return out
    reach = scan.range_max
    candidates = np.flatnonzero(obstacles.distances(pose[:2]) < reach - through)
    if not len(candidates):
        return out
    circles = candidates[candidates < obstacles.n_circles]
    segments = candidates[candidates >= obstacles.n_circles] - obstacles.n_circles
    # Shrunk by the margin (a circle's radius, a segment's ends): a beam grazing an edge that perception or the
    # map drew a little too large says nothing.
    radii = obstacles.radii[circles]
    radii = radii - np.minimum(through, 0.5 * radii)
    starts, ends = obstacles.starts[segments], obstacles.ends[segments]
    run = ends - starts
    length = np.maximum(np.hypot(run[:, 0], run[:, 1]), 1e-12)
    cut = (np.minimum(through, 0.25 * length) / length)[:, None] * run
    # Only the (beam, candidate) pairs where the beam can meet the candidate: any other pair is a miss.
    beam, candidate, expected = fan_hits(pose[:2], pose[2], scan.angle_min, scan.angle_increment, len(scan.ranges),
                                         obstacles.centers[circles], radii, starts + cut, ends - cut)
    measured = np.nan_to_num(scan.ranges, nan=-np.inf)[beam]   # no reading (nan) sees through nothing
    passed = (expected > 0.0) & (expected < reach - through) & (measured > expected + through)
    out[candidates] = np.bincount(candidate[passed], minlength=len(candidates)) >= SEE_THROUGH_BEAMS
    return out
