"""Fusion of a scan with what the robot already believes: the points a believed surface explains, and the
believed obstacles the scan sees through.

- Explained points: a point within EXPLAINED of a believed obstacle's surface, or inside it, is that obstacle
  (the map's, possibly misplaced; one perception added); a point within EXPLAINED of another robot's circle
  (its odometry) or of a known mover's reported circle is that robot or mover. Only the rest can be new.
- Seen through: a believed obstacle is contradicted by a beam that reads farther than the obstacle's surface
  on that beam by more than SEE_THROUGH (the beam passed where the obstacle should be). Only obstacles whose
  surface the beam would reach within range_max - SEE_THROUGH count (beyond, the beam says nothing), and the
  obstacle is shrunk by SEE_THROUGH first (circles' radii, segments' ends: grazing beams say nothing), and a
  map wall's beam must cross its WALL_BAND side to side alongside it; a beam with no reading (NaN) says nothing,
  +inf (no return within range) that its whole length is free. An obstacle contradicted by SEE_THROUGH_BEAMS
  beams of one scan or more is not where the map says (a misplaced obstacle's ghost, or a mover perception once
  took for a still obstacle).
  Vectorised (laser.fan_hits); seen_through_and_nearest also gives each beam's nearest believed surface.
- Pose uncertainty (uncertainty.PoseUncertainty: the scan placed at a pose that may be off): a return may lie its
  slack (translation + yaw x range) beside a mapped surface and still be it (explained_within), and a beam sees
  through a mapped obstacle only past its slack too (circles shrunk, walls' ends cut and their band widened by it).
  Only the map's obstacles: what this robot saw was placed from its own poses, off by the same error.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Obstacles, norm
from fastep_core.perception.uncertainty import PoseUncertainty
from fastep_core.sensing.laser import FanDirections, Scan, fan_hits

__all__ = ['END_SLACK', 'EXPLAINED', 'SEE_THROUGH', 'SEE_THROUGH_BEAMS', 'WALL_BAND', 'explained',
           'explained_by_belief', 'explained_within', 'nearest_surfaces', 'seen_through', 'seen_through_and_nearest',
           'seen_through_circles']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

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
WALL_BAND = EXPLAINED
"""Metres on each side of a map's wall where its true surface may lie (a /map's outline is a cell off the truth): a
beam sees through the wall only when it crosses this band from side to side alongside the wall. Before, a beam
grazing a /map outline a cell off the true wall saw through it: a laser in a doorway dropped a furnished office's
corridor walls along the whole /map (robot harness, office). Not for the walls perception fitted: drawn where
this robot's returns were, they yield to every beam through them (kept, they made FAStep-Route's paths in dense
clutter 8 % longer)."""


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


def explained_by_belief(points: FloatArray, believed: Obstacles, map_segments: int,
                        tolerance: float = EXPLAINED) -> NDArray[np.bool_]:
    """explained(points, seen, no circles, tolerance, map_obstacles=on_map) in one query of believed = Obstacles(map's
    items + seen items), whose first `map_segments` segments are the map's: those with END_SLACK, the rest without
    (+inf). The same answer when every obstacle is finite (Obstacles.near: each pair's own arithmetic)."""
    out = np.zeros(len(points), dtype=bool)
    if not len(points) or not len(believed):
        return out
    slack = np.full(len(believed.starts), np.inf)
    slack[:map_segments] = END_SLACK
    near: NDArray[np.bool_] = believed.near(points, tolerance, slack)
    return near


def explained_within(points: FloatArray, obstacles: Obstacles, within: FloatArray,
                     end_slack: FloatArray) -> NDArray[np.bool_]:
    """Which points (n, 2) lie within their own `within` (n,) of an obstacle's surface (or inside it), a segment
    counting only for points whose foot lies at most their `end_slack` (n,) beyond its ends: explained with a
    tolerance per point (a return's pose slack). Obstacles.near at the largest tolerance finds the few points that
    may be; their distances to every obstacle, with near's arithmetic, decide."""
    out = np.zeros(len(points), dtype=bool)
    if not len(points) or not len(obstacles):
        return out
    maybe = np.flatnonzero(obstacles.near(points, float(within.max()), float(end_slack.max())))
    if not len(maybe):
        return out
    p, tolerance, slack = points[maybe], within[maybe, None], end_slack[maybe, None]
    hit = np.zeros(len(maybe), dtype=bool)
    if obstacles.n_circles:
        gap = norm(p[:, None, 0] - obstacles.centers[:, 0], p[:, None, 1] - obstacles.centers[:, 1]) - obstacles.radii
        hit |= (gap < tolerance).any(axis=1)
    if len(obstacles.starts):
        starts, run = obstacles.starts, obstacles.ends - obstacles.starts
        inv_length2 = np.where((run * run).sum(axis=1) > 0.0, 1.0 / np.maximum((run * run).sum(axis=1), 1e-300), 0.0)
        ax, ay = p[:, None, 0] - starts[:, 0], p[:, None, 1] - starts[:, 1]
        along = (ax * run[:, 0] + ay * run[:, 1]) * inv_length2
        t = np.minimum(np.maximum(along, 0.0), 1.0)
        distance = norm(ax - t * run[:, 0], ay - t * run[:, 1])
        beyond = slack * np.sqrt(inv_length2)          # the end slack in the segment's parameter
        hit |= ((distance < tolerance) & (along >= -beyond) & (along <= 1.0 + beyond)).any(axis=1)
    out[maybe] = hit
    return out


def seen_through(scan: Scan, pose: FloatArray, obstacles: Obstacles, through: float = SEE_THROUGH,
                 directions: FanDirections | None = None, map_walls: int | None = None) -> NDArray[np.bool_]:
    """Which believed obstacles (circles first, as Obstacles orders them) this scan from pose sees through;
    `through`: SEE_THROUGH (module docstring), or less for a shape fitted to this very scan, whose surface is
    known to the noise. `directions`: the scan's laser.fan_directions from pose, when made already. `map_walls`:
    how many of the walls (the first ones) are the map's, whose beams must cross their WALL_BAND (None: all)."""
    if not len(obstacles):
        return np.zeros(0, dtype=bool)
    walls = len(obstacles.starts) if map_walls is None else map_walls
    return _seen_through(scan, pose, obstacles.distances(pose[:2]), obstacles.centers, obstacles.radii,
                         obstacles.starts, obstacles.ends, through, directions, False, walls)[0]


def seen_through_circles(scan: Scan, pose: FloatArray, centres: FloatArray, radii: FloatArray,
                         through: float = SEE_THROUGH, directions: FanDirections | None = None) -> NDArray[np.bool_]:
    """seen_through of the circles (centres (k, 2), radii (k,)) as Obstacles of them, from the arrays themselves."""
    if not len(radii):
        return np.zeros(0, dtype=bool)
    distances = norm(pose[0] - centres[:, 0], pose[1] - centres[:, 1]) - radii    # Obstacles.distances' arithmetic
    return _seen_through(scan, pose, distances, centres, radii, _NO_POINTS, _NO_POINTS, through, directions, False)[0]


def nearest_surfaces(scan: Scan, pose: FloatArray, obstacles: Obstacles,
                     directions: FanDirections | None = None) -> FloatArray:
    """Each beam's distance to the nearest surface of the obstacles it meets ahead (+inf: none)."""
    nearest = np.full(len(scan.ranges), np.inf)
    circles = obstacles.n_circles
    beam, _, expected = fan_hits(pose[:2], pose[2], scan.angle_min, scan.angle_increment, len(scan.ranges),
                                 obstacles.centers[:circles], obstacles.radii[:circles], obstacles.starts,
                                 obstacles.ends, directions)
    np.minimum.at(nearest, beam, np.where(expected > 0.0, expected, np.inf))
    return nearest


def seen_through_and_nearest(scan: Scan, pose: FloatArray, obstacles: Obstacles,
                             directions: FanDirections | None = None, map_walls: int | None = None,
                             uncertainty: PoseUncertainty | None = None,
                             map_circles: int = 0) -> tuple[NDArray[np.bool_], FloatArray]:
    """seen_through(scan, pose, obstacles, map_walls=map_walls) and nearest_surfaces(scan, pose, obstacles), bit for
    bit, from one fan_hits call: each obstacle cast once shrunk (seen_through's) and once as it is (fan_hits casts
    each one on its own beams, so its pairs are those of a call of its own). `uncertainty`: of the pose, for the
    map's obstacles (the first `map_circles` circles and `map_walls` walls; module docstring)."""
    if not len(obstacles):
        return np.zeros(0, dtype=bool), np.full(len(scan.ranges), np.inf)
    walls = len(obstacles.starts) if map_walls is None else map_walls
    through, nearest = _seen_through(scan, pose, obstacles.distances(pose[:2]), obstacles.centers, obstacles.radii,
                                     obstacles.starts, obstacles.ends, SEE_THROUGH, directions, True, walls,
                                     uncertainty, map_circles)
    assert nearest is not None
    return through, nearest


_NO_POINTS = np.zeros((0, 2))


def _across_band(pose: FloatArray, scan: Scan, beam: IntArray, wall: IntArray, measured: FloatArray,
                 starts: FloatArray, units: FloatArray, lengths: FloatArray,
                 directions: FanDirections | None, band: float | FloatArray = WALL_BAND) -> NDArray[np.bool_]:
    """Which beams that read past a believed wall (wall: its index in starts, units and lengths, the walls' start
    points, unit directions and lengths) crossed the wall's band (WALL_BAND, or one per beam) from side to side
    alongside the wall: a true surface within the band along the wall would have stopped them. A beam that starts
    or ends inside the band, or crosses it beyond an end of the wall (round a corner the truth may have), says
    nothing."""
    if directions is None:
        angles = pose[2] + scan.angle_min + scan.angle_increment * beam.astype(float)
        cos, sin = np.cos(angles), np.sin(angles)
    else:
        cos, sin = directions[1][beam], directions[2][beam]
    u = units[wall]
    across = np.abs(u[:, 0] * sin - u[:, 1] * cos)             # the sine of the angle between beam and wall
    along = u[:, 0] * cos + u[:, 1] * sin
    rel_x, rel_y = pose[0] - starts[wall, 0], pose[1] - starts[wall, 1]
    offset = np.abs(u[:, 0] * rel_y - u[:, 1] * rel_x)         # the scanner's distance from the wall's line
    at = u[:, 0] * rel_x + u[:, 1] * rel_y                     # ... and where it lies along the wall
    with np.errstate(divide='ignore', invalid='ignore'):
        enter, leave = (offset - band) / across, (offset + band) / across   # along the beam
    first, last = at + enter * along, at + leave * along       # along the wall
    crossed: NDArray[np.bool_] = (offset >= band) & (measured >= leave) & \
        (np.minimum(first, last) >= 0.0) & (np.maximum(first, last) <= lengths[wall])
    return crossed


def _seen_through(scan: Scan, pose: FloatArray, distances: FloatArray, centres: FloatArray, radii: FloatArray,
                  starts: FloatArray, ends: FloatArray, through: float, directions: FanDirections | None,
                  surfaces: bool, map_walls: int = 0, uncertainty: PoseUncertainty | None = None,
                  map_circles: int = 0) -> tuple[NDArray[np.bool_], FloatArray | None]:
    """seen_through of the circles and segments (distances: Obstacles.distances from pose), and with `surfaces`
    nearest_surfaces too, the obstacles as they are cast in the same fan_hits call after the shrunk ones. The first
    `map_walls` segments are the map's (WALL_BAND), and with `uncertainty` the first `map_circles` circles and those
    walls are shrunk by their slack too (module docstring)."""
    n_circles = len(radii)
    out = np.zeros(n_circles + len(starts), dtype=bool)
    reach = scan.range_max
    candidates = np.flatnonzero(distances < reach - through)
    tolerant = uncertainty is not None and not uncertainty.none
    extra = np.zeros(len(distances))    # each map obstacle's slack (tolerant)
    if tolerant:
        assert uncertainty is not None
        # A map obstacle's slack at its nearest point (a lower bound along it): one that shrinks to nothing, the
        # scan cannot see through at this uncertainty.
        mapped = np.concatenate([np.arange(min(map_circles, n_circles)), n_circles + np.arange(map_walls)])
        extra[mapped] = uncertainty.slack(np.maximum(distances[mapped], 0.0))
        keep = np.ones(len(candidates), dtype=bool)
        is_circle = candidates < n_circles
        keep[is_circle] = radii[candidates[is_circle]] - np.minimum(through, 0.5 * radii[candidates[is_circle]]) > \
            extra[candidates[is_circle]]
        wall = candidates[~is_circle] - n_circles
        run_of = ends[wall] - starts[wall]
        keep[~is_circle] = np.hypot(run_of[:, 0], run_of[:, 1]) - \
            2.0 * np.minimum(through, 0.25 * np.hypot(run_of[:, 0], run_of[:, 1])) > 2.0 * extra[candidates[~is_circle]]
        candidates = candidates[keep]
    if not len(candidates) and not surfaces:
        return out, None
    circles = candidates[candidates < n_circles]
    segments = candidates[candidates >= n_circles] - n_circles
    # Shrunk by the margin (a circle's radius, a segment's ends): a beam grazing an edge that perception or the
    # map drew a little too large says nothing.
    shrunk = radii[circles]
    shrunk = shrunk - np.minimum(through, 0.5 * shrunk)
    low, high = starts[segments], ends[segments]
    run = high - low
    length = np.maximum(np.hypot(run[:, 0], run[:, 1]), 1e-12)
    cut = (np.minimum(through, 0.25 * length) / length)[:, None] * run
    if tolerant:
        shrunk = shrunk - extra[circles]
        cut = cut + (extra[n_circles + segments] / length)[:, None] * run
    cast_centres, cast_radii, cast_starts, cast_ends = centres[circles], shrunk, low + cut, high - cut
    if surfaces:
        cast_centres, cast_radii = np.concatenate([cast_centres, centres]), np.concatenate([cast_radii, radii])
        cast_starts, cast_ends = np.concatenate([cast_starts, starts]), np.concatenate([cast_ends, ends])
    # Only the (beam, candidate) pairs where the beam can meet the candidate: any other pair is a miss.
    beam, candidate, expected = fan_hits(pose[:2], pose[2], scan.angle_min, scan.angle_increment, len(scan.ranges),
                                         cast_centres, cast_radii, cast_starts, cast_ends, directions)
    nearest = None
    if surfaces:
        shrunk_circles, cast_circles = len(circles), len(circles) + n_circles
        mine = (candidate < shrunk_circles) | ((candidate >= cast_circles) &
                                               (candidate < cast_circles + len(segments)))
        theirs = ~mine
        nearest = np.full(len(scan.ranges), np.inf)
        whole = expected[theirs]
        np.minimum.at(nearest, beam[theirs], np.where(whole > 0.0, whole, np.inf))
        beam, expected = beam[mine], expected[mine]
        candidate = candidate[mine]
        candidate = np.where(candidate < shrunk_circles, candidate, candidate - n_circles)
    # A beam with no reading (nan) sees through nothing: nan > x is false.
    measured = scan.ranges[beam]
    passed = (expected > 0.0) & (expected < reach - through) & (measured > expected + through)
    # The map's walls: candidates len(circles) + k for the k-th segment candidate, whose own index is segments[k].
    walls = passed & (candidate >= len(circles))
    walls[walls] = segments[candidate[walls] - len(circles)] < map_walls
    if walls.any():
        band: float | FloatArray = WALL_BAND
        reading = measured[walls]
        if tolerant:
            assert uncertainty is not None
            band = WALL_BAND + uncertainty.slack(expected[walls])
            # No return within range (+inf) shows the beam free to its range, not beyond: along a grazing beam the
            # band's far side may lie farther (a heading a degree off puts a parallel wall's returns there).
            reading = np.minimum(reading, reach)
        passed[walls] = _across_band(pose, scan, beam[walls], candidate[walls] - len(circles), reading,
                                     low, run / length[:, None], length, directions, band)
    out[candidates] = np.bincount(candidate[passed], minlength=len(candidates)) >= SEE_THROUGH_BEAMS
    return out, nearest
