"""What a robot believes about its world, kept apart from the truth, and the perception loop that updates it.

A robot with a sensor starts believing its map (the known obstacles, misplaced ones where the map says). Each
control tick it scans the true world (the simulator, or a LaserScan on a real robot) and `Perception.update`:

1. turns the readings into map-frame points (segmentation.scan_points);
2. drops from the belief every obstacle the scan sees through (fusion.seen_through: a misplaced obstacle's
   ghost, or a mover once taken for a still obstacle);
3. sets aside the points a believed obstacle, another robot (its odometry) or a known mover explains
   (fusion.explained);
4. clusters the rest along the beam order (segmentation.segment) and fits circles, or walls where no circle
   fits and the cluster is within WALL_RANGE of the range (shapes.shapes);
5. tracks the circles with a constant-velocity Kalman filter (tracking.Tracker);
6. believes in still obstacles: walls at once (straight walls merged with the collinear pieces it already
   has; not a piece on a moving track, which is movers seen merged: the track coasts, kept alive by the
   points near it), circles once their track has stood still (speed below STILL_SPEED) for STILL_TIME seconds
   on end (such a circle overlapping a map circle of about its size replaces it: the map's was misplaced);
7. reports the other confirmed tracks as movers: OtherRobot('track K', position, velocity, radius), the way
   known movers and other robots reach planners.

The result is a `Belief`: a World for the navigator (changed, as a new object, only when the still obstacles
it believes in change, so planners replan only then) and the tracked movers. Nothing here draws random
numbers: the scanner's noise is drawn by whoever scans (the simulator: `sensor_generator`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Circle, Obstacle, Obstacles, Segment, point_segment_distance
from fastep_core.perception.fusion import explained, seen_through
from fastep_core.perception.segmentation import scan_points, segment
from fastep_core.perception.shapes import WALL_TOLERANCE, shapes
from fastep_core.perception.tracking import Tracker, TrackParams
from fastep_core.planning.others import OtherRobot
from fastep_core.sensing.laser import LaserSpec, Scan
from fastep_core.world import World

__all__ = ['MERGE_GAP', 'MERGE_REACH', 'PERCEPTION_MARGIN', 'SENSOR_STREAM', 'STILL_SPEED', 'STILL_TIME',
           'WALL_RANGE', 'Belief', 'Perception', 'heading', 'perception_margin', 'sensor_generator', 'track_name']

FloatArray = NDArray[np.float64]

STILL_SPEED = 0.15
"""m/s: a confirmed track slower than this is a still obstacle (the families' movers go 0.3 m/s and more)."""
STILL_TIME = 1.5
"""Seconds a track must have been slower than STILL_SPEED, without a break, before it counts as still."""
WALL_RANGE = 0.6
"""Share of the scanner's range within which a cluster no circle fits is believed a wall (shapes.shapes)."""
MERGE_GAP = 0.5
"""Metres: a new wall piece this close to a collinear believed wall extends it instead of adding a segment."""
MERGE_REACH = 0.3
"""Metres beyond a moving track's radius within which a wall piece is that mover seen merged (Perception)."""
MERGE_MARGIN = 1e-6
"""Metres: rounding margin of Perception._wall_candidates, far above the 1e-15 m its arithmetic may differ by."""
SENSOR_STREAM = 0x736E73   # 'sns': spawn key of the scanners' noise streams, far above any robot's index


PERCEPTION_MARGIN = 0.02
"""Metres the guard keeps beyond a robot's radius from the surfaces it believes from its scans (at least; three
times the range noise if more): a fitted wall's end is known to a beam gap, a surface to the noise.
FAStep-Route rounding a seen wall's end at the guard's limit touched the true end by 0.05 mm, the belief's end
8 mm short (unknown_obstacles:1000015, docs/dynamic_world.md)."""


def perception_margin(spec: LaserSpec) -> float:
    """The guard's margin beyond the radius for a robot that plans in what this scanner shows."""
    return max(PERCEPTION_MARGIN, 3.0 * spec.noise)


def sensor_generator(seed: int, robot: int) -> np.random.Generator:
    """The Generator of robot `robot`'s scanner noise in a run of `seed`: a stream no swarm or map uses."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(SENSOR_STREAM, robot)))


def track_name(track_id: int) -> str:
    """What planners call a tracked mover ('track 4')."""
    return f'track {track_id}'


def heading(model: str, state: Sequence[float] | FloatArray) -> float:
    """The scanner's heading (DESIGN.md, sensor): a point mass looks along +x; the others along theta (state[2])."""
    return 0.0 if model == 'point_mass' else float(state[2])


@dataclass(frozen=True)
class Belief:
    """What one robot believes at time t (never the truth): the world it plans in and the movers it tracks."""

    t: float
    world: World                               # the map's obstacles it still believes, plus the ones it saw
    map_obstacles: tuple[Obstacle, ...]        # of the map's obstacles, those not seen through
    seen_obstacles: tuple[Obstacle, ...]       # still obstacles perception added (circles and wall segments)
    dropped: tuple[Obstacle, ...]              # the map's obstacles a scan saw through
    movers: tuple[OtherRobot, ...]             # confirmed tracks that move (or have not yet stood still)
    points: FloatArray                         # this scan's points nothing believed explained (for figures)


class Perception:
    """One robot's perception over a run: its belief, its tracker, the map it started from."""

    def __init__(self, spec: LaserSpec, map_world: World, track_params: TrackParams | None = None) -> None:
        self.spec = spec
        self.map_world = map_world
        self.map_items: list[Obstacle] = list(map_world.obstacle_list)
        self.seen_items: list[Obstacle] = []
        self.dropped: list[Obstacle] = []
        self.tracker = Tracker(track_params)
        self._obstacle_cache: dict[str, tuple[tuple[int, ...], Obstacles]] = {}
        self.slow_since: dict[int, float] = {}   # track id -> since when it has been slower than STILL_SPEED
        self.world = map_world
        self.belief = Belief(0.0, map_world, tuple(self.map_items), (), (), (), np.zeros((0, 2)))

    def update(self, t: float, pose: Sequence[float], scan: Scan, others: Sequence[OtherRobot] = ()) -> Belief:
        """Fold one scan taken at pose (x, y, heading) into the belief (module docstring); others: the other
        robots (odometry) and known movers as the robot is told of them."""
        pose_array = np.asarray(pose, dtype=float)[:3]
        changed = False
        believed = self.world.obstacles
        through = seen_through(scan, pose_array, believed)
        if through.any():
            gone = {id(item) for item, drop in zip(believed.items, through) if drop}
            self.dropped += [o for o in self.map_items if id(o) in gone]
            self.map_items = [o for o in self.map_items if id(o) not in gone]
            self.seen_items = [o for o in self.seen_items if id(o) not in gone]
            believed = Obstacles(self.map_items + self.seen_items)
            changed = True
        points, beams = scan_points(scan, pose_array)
        centres = np.array([o.position for o in others], dtype=float).reshape(-1, 2)
        radii = np.array([o.radius for o in others], dtype=float)
        new = ~explained(points, self._obstacles('seen'), centres, radii, map_obstacles=self._obstacles('map'))
        points, beams = points[new], beams[new]
        labels = segment(scan, points, beams, self.spec.noise, self.spec.full_turn)
        found = shapes(points, beams, labels, pose_array[:2], self.spec.noise, WALL_RANGE * self.spec.range,
                       abs(scan.angle_increment))
        tracker = self.tracker
        tracker.update(t, found.centres, found.radii)
        starts, ends, merged = self._merged_movers(t, points, found.starts, found.ends)
        # Tracks that stood still long enough become still obstacles: slow for STILL_TIME without a break, so a
        # mover whose velocity estimate dipped for a few scans (two movers merged into one detection) stays one.
        speed = np.hypot(tracker.states[:, 2], tracker.states[:, 3])
        slow = (speed < STILL_SPEED) & ~np.isin(tracker.ids, merged) if len(merged) else speed < STILL_SPEED
        self.slow_since = {int(i): self.slow_since.get(int(i), t) for i in tracker.ids[slow]}
        since = np.array([self.slow_since.get(int(i), math.inf) for i in tracker.ids])
        still = tracker.confirmed & slow & (t - since >= STILL_TIME) & (tracker.seen == t)
        if still.any():
            found_circles = [Circle((float(s[0]), float(s[1])), float(r))
                             for s, r in zip(tracker.states[still], tracker.radii[still])]
            self._replace_map_circles(found_circles)
            self.seen_items += found_circles
            tracker.keep(~still)
            changed = True
        for start, end in zip(starts, ends):
            self._add_wall(start, end)
            changed = True
        if changed:
            self.world = World(self.map_world.workspace, tuple(self.map_items + self.seen_items))
        confirmed = np.flatnonzero(tracker.confirmed)
        movers = tuple(OtherRobot(track_name(int(tracker.ids[k])),
                                  (float(tracker.states[k, 0]), float(tracker.states[k, 1])),
                                  (float(tracker.states[k, 2]), float(tracker.states[k, 3])), float(tracker.radii[k]),
                                  mover=True)
                       for k in confirmed)
        self.belief = Belief(t, self.world, tuple(self.map_items), tuple(self.seen_items), tuple(self.dropped),
                             movers, points)
        return self.belief

    def _obstacles(self, which: str) -> Obstacles:
        """The believed obstacles from the map ('map') or from the scans ('seen'), as Obstacles, made again only
        when they changed."""
        items = self.map_items if which == 'map' else self.seen_items
        key = tuple(map(id, items))
        cached = self._obstacle_cache.get(which)
        if cached is None or cached[0] != key:
            cached = self._obstacle_cache[which] = (key, Obstacles(items))
        return cached[1]

    def _merged_movers(self, t: float, points: FloatArray, starts: FloatArray,
                       ends: FloatArray) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
        """After the tracker's update: the wall pieces that are walls, and the ids of the moving tracks seen merged.

        Two movers near each other (or one passing an unknown obstacle) show one outline no circle fits: no
        detection for either track, which died after MAX_COAST, and once near enough the outline was believed a
        wall, which then explained the movers' points wherever they went near it (crossing_movers:1000022: both
        unknown movers lost for good, and the robot touched one). So a confirmed track that moves and got no
        detection this scan, but has unexplained points within MERGE_REACH of its predicted disc, was seen,
        merged: it coasts on its velocity, alive, and is never made a still obstacle meanwhile; and a wall piece
        within MERGE_REACH of a moving track is that mover, not a wall.
        """
        tracker = self.tracker
        moving = tracker.confirmed & (np.hypot(tracker.states[:, 2], tracker.states[:, 3]) >= STILL_SPEED)
        if not moving.any():
            return starts, ends, np.zeros(0, dtype=np.int64)
        centres, reach = tracker.states[moving, :2], tracker.radii[moving] + MERGE_REACH
        near_points: NDArray[np.bool_] = np.zeros(int(moving.sum()), dtype=bool)
        if len(points):
            gaps = np.hypot(points[:, None, 0] - centres[None, :, 0], points[:, None, 1] - centres[None, :, 1])
            near_points = np.asarray((gaps < reach[None, :]).any(axis=0))
        walls: NDArray[np.bool_] = np.ones(len(starts), dtype=bool)
        if len(starts):
            on_track = point_segment_distance(centres[None, :, :], starts[:, None, :], ends[:, None, :]) < reach
            walls = np.asarray(~on_track.any(axis=1))
            near_points = near_points | on_track.any(axis=0)
        merged = near_points & (tracker.seen[moving] < t)
        ids = tracker.ids[moving][merged]
        if len(ids):
            tracker.seen[np.isin(tracker.ids, ids)] = t
        return starts[walls], ends[walls], ids

    def _replace_map_circles(self, found: list[Circle]) -> None:
        """A still circle perception found where the map has one of about its size, overlapping it, is that
        one where it really is: the map's (misplaced) circle is dropped for it."""
        for circle in found:
            for item in self.map_items:
                if isinstance(item, Circle) and 0.5 <= circle.radius / item.radius <= 2.0 and \
                        math.dist(item.center, circle.center) < item.radius + circle.radius:
                    self.map_items.remove(item)
                    self.dropped.append(item)
                    break

    def _add_wall(self, start: FloatArray, end: FloatArray) -> None:
        """Believe in a wall piece: extend a collinear believed wall it continues, else add it."""
        new = np.array([start, end])
        for k in self._wall_candidates(new):
            item = self.seen_items[k]
            if not isinstance(item, Segment):
                continue
            a, b = np.array(item.start), np.array(item.end)
            run = b - a
            length = math.hypot(run[0], run[1])
            if length <= 0.0:
                continue
            unit = run / length
            offset = new - a
            off_line = np.abs(unit[0] * offset[:, 1] - unit[1] * offset[:, 0])
            along = offset @ unit
            if off_line.max() > WALL_TOLERANCE or along.max() < -MERGE_GAP or along.min() > length + MERGE_GAP:
                continue
            low, high = min(0.0, float(along.min())), max(length, float(along.max()))
            p, q = a + low * unit, a + high * unit
            self.seen_items[k] = Segment((float(p[0]), float(p[1])), (float(q[0]), float(q[1])))
            return
        self.seen_items.append(Segment((float(start[0]), float(start[1])), (float(end[0]), float(end[1]))))

    def _wall_candidates(self, new: FloatArray) -> list[int]:
        """Indices, in order, of the believed walls that the piece `new` (2, 2) may continue: _add_wall's test for
        all walls at once, with a margin of MERGE_MARGIN that only lets more through, so that its exact test (one
        wall at a time, as before) runs on these few and gives the same answer as on all of them."""
        walls = [(k, item) for k, item in enumerate(self.seen_items) if isinstance(item, Segment)]
        if not walls:
            return []
        ends = np.array([(item.start, item.end) for _, item in walls])                              # (w, 2, 2)
        a = ends[:, 0]
        run = ends[:, 1] - a
        length = np.hypot(run[:, 0], run[:, 1])
        unit = run / np.where(length > 0.0, length, 1.0)[:, None]
        offset = new[None, :, :] - a[:, None, :]                                                    # (w, 2, 2)
        off_line = np.abs(unit[:, None, 0] * offset[..., 1] - unit[:, None, 1] * offset[..., 0])
        along = unit[:, None, 0] * offset[..., 0] + unit[:, None, 1] * offset[..., 1]
        # Negated as _add_wall's test is, so that a nan lets a wall through here as it does there.
        margin = MERGE_GAP + MERGE_MARGIN
        maybe = ~((off_line.max(axis=1) > WALL_TOLERANCE + MERGE_MARGIN) | (along.max(axis=1) < -margin) |
                  (along.min(axis=1) > length + margin))
        return [walls[k][0] for k in np.flatnonzero(maybe)]
