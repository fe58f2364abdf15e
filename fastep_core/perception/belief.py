"""What a robot believes about its world, kept apart from the truth, and the perception loop that updates it.

A robot with a sensor starts believing its map. Each tick `Perception.update` turns the scan into map-frame points
(segmentation.scan_points); drops believed obstacles the scan sees through (fusion.seen_through); sets aside points a
believed obstacle, robot or known mover explains, unless IN_FRONT of the believed surface (`_in_front`); clusters the
rest (segmentation.segment) and fits circles, or walls within WALL_RANGE (shapes.shapes); tracks circles with a
constant-velocity Kalman filter (tracking.Tracker); believes walls at once and a confirmed track's circle while not
found moving, for good after STILL_TIME below STILL_SPEED (replacing a map circle of its size it overlaps); and
reports as movers only tracks gone MOVER_DISTANCE into space earlier scans saw free (`_came_into_free_space`), as
OtherRobot('track K', ...). The result is a `Belief`: a World, a new object only when the still obstacles change (so
planners replan only then), and the tracked movers. No random numbers are drawn here (the scanner's noise is drawn
by whoever scans). Why shapes and not a grid, and the costmap-like rules: docs/architecture.md, "What a laser shows".

A scan placed at a pose that may be off (`uncertainty`: uncertainty.PoseUncertainty, per Perception or per scan)
has each return's slack (translation + yaw x range) added where it meets the map: a return within EXPLAINED plus
its slack of a mapped obstacle is that obstacle (fusion.explained_within), IN_FRONT of one only past its slack too,
and a mapped obstacle is seen through only past its slack (fusion). With none (the default) perception is what it
was, bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Circle, Obstacle, Obstacles, Segment, point_segment_distance
from fastep_core.perception.fusion import (
    END_SLACK,
    EXPLAINED,
    explained,
    explained_by_belief,
    explained_within,
    nearest_surfaces,
    seen_through_and_nearest,
    seen_through_circles,
)
from fastep_core.perception.segmentation import scan_points, segment
from fastep_core.perception.shapes import shapes
from fastep_core.perception.tracking import Tracker, TrackParams
from fastep_core.perception.uncertainty import NO_UNCERTAINTY, PoseUncertainty
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.recovery.back_up import RecentScans
from fastep_core.sensing.laser import FanDirections, LaserSpec, Scan, fan_directions
from fastep_core.world import World

__all__ = ['FITTED_THROUGH', 'FREE_MARGIN', 'IN_FRONT', 'MERGE_GAP', 'MERGE_REACH', 'MERGE_TOLERANCE', 'MOVER_DISTANCE',
           'MOVER_FREE_POINTS', 'PERCEPTION_MARGIN', 'RECENT_SCANS', 'SENSOR_STREAM', 'STANDING_SHIFT', 'STILL_SPEED',
           'STILL_TIME', 'WALL_RANGE', 'Belief', 'BelievedWorld', 'Perception', 'heading', 'perception_margin',
           'sensor_generator', 'track_name']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
NO_CENTRES, NO_RADII, NO_OBSTACLES = np.zeros((0, 2)), np.zeros(0), Obstacles()

STILL_SPEED = 0.15
"""m/s: a confirmed track slower than this is a still obstacle (the families' movers go 0.3 m/s and more)."""
STILL_TIME = 1.5
"""Seconds a track must have been slower than STILL_SPEED, without a break, before it counts as still."""
WALL_RANGE = 0.6
"""Share of the scanner's range within which a cluster no circle fits is believed a wall (shapes.shapes)."""
FITTED_THROUGH = 0.03
"""Metres (or 3 noise sigmas, if more) a beam of the scan a circle was fitted to must pass through the disc, shrunk
by as much, for the disc to be no circle: a cluster of poles fits a disc that bulges over the gaps between them."""
IN_FRONT = 0.05
"""Metres (or 4 noise sigmas, if more) a return must lie in front of the believed surface on its beam to be a
surface the belief lacks (Perception._in_front): a wall is believed at its nearest return (shapes._in_front_of),
so its own returns lie in front of it by the noise alone."""
MOVER_DISTANCE = 0.3
"""Metres a confirmed track must have gone from where it was confirmed (at STILL_SPEED or more) to be a mover: the
centre fitted to a still thing wanders as the robot's viewpoint and the noise change, by centimetres (a pole) to
a decimetre or two (a cluster of them); a mover keeps going."""
STANDING_SHIFT = 0.1
"""Metres a standing track's estimate may drift from its circle in the world before the circle follows it."""
MERGE_TOLERANCE = 0.03
"""Metres off a believed wall's line within which a new piece continues it (farther: a surface of its own, in
front of the wall or behind it)."""
MERGE_GAP = 0.5
"""Metres: a new wall piece this close to a collinear believed wall extends it instead of adding a segment."""
MERGE_REACH = 0.3
"""Metres beyond a moving track's radius within which a wall piece is that mover seen merged (Perception)."""
MERGE_MARGIN = 1e-6
"""Metres: rounding margin of Perception._wall_candidates, far above the 1e-15 m its arithmetic may differ by."""
FREE_MARGIN = 0.1
"""Metres from anything earlier scans did not see free a point must lie to be in space they saw free (the noise, a
beam grazing a surface, the odometry's error between two scans)."""
MOVER_FREE_POINTS = 3
"""Points of a track that must lie where an earlier scan saw free space before it counts as a mover: a mover
comes into space that was free; a still thing's surface is where beams always stopped."""
RECENT_SCANS = 30.0
"""Seconds of scans whose free space counts as evidence (a mover's, and the way a reversing robot may take)."""
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
    """The scanner's heading (docs/scenarios.md, sensor): a point mass looks along +x; the others along theta
    (state[2])."""
    return 0.0 if model == 'point_mass' else float(state[2])


@dataclass(frozen=True)
class BelievedWorld(World):
    """The World a robot with a sensor plans in, knowing which of its obstacles the laser showed (`seen_obstacles`,
    the rest are the map's) and the map it started from (`map_obstacles`, those a scan saw through too): what a
    failure names (planning/exact_path.in_the_way)."""

    seen_obstacles: tuple[Obstacle, ...] = field(default=(), compare=False)
    map_obstacles: tuple[Obstacle, ...] = field(default=(), compare=False)


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

    def __init__(self, spec: LaserSpec, map_world: World, track_params: TrackParams | None = None,
                 uncertainty: PoseUncertainty = NO_UNCERTAINTY) -> None:
        self.spec = spec
        self.uncertainty = uncertainty   # of the poses scans are placed at, unless a scan brings its own
        self.map_world = map_world
        self.map_items: list[Obstacle] = list(map_world.obstacle_list)
        self.seen_items: list[Obstacle] = []
        self.dropped: list[Obstacle] = []
        self.tracker = Tracker(track_params)
        self._obstacle_cache: dict[str, tuple[tuple[int, ...], Obstacles]] = {}
        self.slow_since: dict[int, float] = {}   # track id -> since when it has been slower than STILL_SPEED
        self.standing: dict[int, Circle] = {}     # track id -> its circle in the world while not found moving
        self.recent = RecentScans(RECENT_SCANS)   # the free space its earlier scans saw
        self.returns: FloatArray = np.zeros((0, 2))   # the latest scan's returns (map frame)
        self.world = map_world
        self.belief = Belief(0.0, map_world, tuple(self.map_items), (), (), (), np.zeros((0, 2)))

    def update(self, t: float, pose: Sequence[float], scan: Scan, others: Sequence[OtherRobot] = (),
               uncertainty: PoseUncertainty | None = None) -> Belief:
        """Fold one scan taken at pose (x, y, heading) into the belief (module docstring); others: the other
        robots (odometry) and known movers as the robot is told of them; uncertainty: of this pose (None: the
        Perception's)."""
        pose_array = np.asarray(pose, dtype=float)[:3]
        told = self.uncertainty if uncertainty is None else uncertainty
        tolerant = None if told.none or not self.map_items else told
        changed = False
        believed = self._obstacles('believed')
        # The beams' directions once for every cast of this scan; each beam's nearest believed surface from the
        # cast that finds what the scan sees through (_in_front's, while that drops nothing).
        directions = fan_directions(pose_array[2], scan.angle_min, scan.angle_increment, len(scan.ranges))
        surfaces: FloatArray | None
        on_map = self._obstacles('map')
        map_walls = len(on_map.starts)   # believed: the map's items first, so its walls (and circles) first
        through, surfaces = seen_through_and_nearest(scan, pose_array, believed, directions, map_walls, tolerant,
                                                     on_map.n_circles)
        if through.any():
            surfaces = None
            gone = {id(item) for item, drop in zip(believed.items, through) if drop}
            self.dropped += [o for o in self.map_items if id(o) in gone]
            self.map_items = [o for o in self.map_items if id(o) not in gone]
            self.seen_items = [o for o in self.seen_items if id(o) not in gone]
            changed = True
            believed = self._obstacles('believed')
        points, beams = scan_points(scan, pose_array)
        self.returns = points   # all of them: the guard's (planning/safety/guard.py)
        centres = np.array([o.position for o in others], dtype=float).reshape(-1, 2)
        radii = np.array([o.radius for o in others], dtype=float)
        # New: what no robot or mover explains, and no believed still obstacle either, unless it lies well in front
        # of the believed surface on its beam (a surface the belief lacks).
        on_map = self._obstacles('map')
        if math.isfinite(believed.scale):   # the map's and the seen obstacles in one query
            still = explained_by_belief(points, believed, len(on_map.starts))
        else:
            still = explained(points, self._obstacles('seen'), NO_CENTRES, NO_RADII, map_obstacles=on_map)
        if tolerant is not None:   # within its slack of a mapped surface: that surface, off by the pose's error
            slack = tolerant.slack(scan.ranges[beams])
            maybe = ~still
            still[maybe] = explained_within(points[maybe], on_map, EXPLAINED + slack[maybe], END_SLACK + slack[maybe])
        still &= ~self._in_front(scan, pose_array, points, beams, believed, directions, surfaces, tolerant)
        new = ~still & ~explained(points, NO_OBSTACLES, centres, radii)
        points, beams = points[new], beams[new]
        labels = segment(scan, points, beams, self.spec.noise, self.spec.full_turn)

        def seen_free(circle_centres: FloatArray, circle_radii: FloatArray) -> NDArray[np.bool_]:
            return seen_through_circles(scan, pose_array, circle_centres, circle_radii,
                                        max(FITTED_THROUGH, 3.0 * self.spec.noise), directions)

        found = shapes(points, beams, labels, pose_array[:2], self.spec.noise, WALL_RANGE * self.spec.range,
                       abs(scan.angle_increment), seen_free)
        tracker = self.tracker
        tracker.update(t, found.centres, found.radii)
        starts, ends, merged = self._merged_movers(t, points, found.starts, found.ends)
        speed = np.hypot(tracker.states[:, 2], tracker.states[:, 3])
        # A mover on consistent evidence only: confirmed, going at STILL_SPEED or more, and gone MOVER_DISTANCE
        # from where it was confirmed (a fit's centre that wanders with the viewpoint or the noise does not).
        gone_from = np.hypot(*(tracker.states[:, :2] - tracker.origins).T)
        candidates = tracker.confirmed & ~tracker.moved & (speed >= STILL_SPEED) & (gone_from >= MOVER_DISTANCE)
        if candidates.any():
            tracker.moved[candidates] = self._came_into_free_space(points, tracker.states[candidates, :2],
                                                                   tracker.radii[candidates])
        # Tracks that stood still long enough become still obstacles: slow for STILL_TIME without a break, so a
        # mover whose velocity estimate dipped for a few scans (two movers merged into one detection) stays one.
        slow = (speed < STILL_SPEED) & ~np.isin(tracker.ids, merged) if len(merged) else speed < STILL_SPEED
        self.slow_since = {int(i): self.slow_since.get(int(i), t) for i in tracker.ids[slow]}
        since = np.array([self.slow_since.get(int(i), math.inf) for i in tracker.ids])
        still = tracker.confirmed & slow & (t - since >= STILL_TIME) & (tracker.seen == t)
        if still.any():
            found_circles = [self._standing_circle(int(i), s, float(r)) for i, s, r in
                             zip(tracker.ids[still], tracker.states[still], tracker.radii[still])]
            self._replace_map_circles(found_circles)
            self.seen_items += found_circles
            tracker.keep(~still)
            changed = True
        changed |= self._update_standing()
        if len(starts):
            self._add_walls(starts, ends)
            changed = True
        items = tuple(self.map_items + self.seen_items + list(self.standing.values()))
        if changed and tuple(map(id, items)) != tuple(map(id, self.world.obstacle_list)):
            # A new World only when what it holds changed (not for a standing circle made still, the same one):
            # planners replan on a new one.
            self.world = BelievedWorld(self.map_world.workspace, items, items[len(self.map_items):],
                                       self.map_world.obstacle_list)
        moving = np.flatnonzero(tracker.confirmed & tracker.moved)
        movers = tuple(OtherRobot(track_name(int(tracker.ids[k])),
                                  (float(tracker.states[k, 0]), float(tracker.states[k, 1])),
                                  (float(tracker.states[k, 2]), float(tracker.states[k, 3])), float(tracker.radii[k]),
                                  mover=True)
                       for k in moving)
        self.belief = Belief(t, self.world, tuple(self.map_items),
                             tuple(self.seen_items + list(self.standing.values())), tuple(self.dropped), movers,
                             points)
        self.recent.add(scan, pose_array)
        return self.belief

    def _in_front(self, scan: Scan, pose: FloatArray, points: FloatArray, beams: IntArray, believed: Obstacles,
                  directions: FanDirections, nearest: FloatArray | None,
                  uncertainty: PoseUncertainty | None = None) -> NDArray[np.bool_]:
        """Which returns lie IN_FRONT or more in front of every believed still obstacle on their beam: a surface
        the belief lacks, nearer than what it has there (a cluster of poles fitted a little small, a wall a little
        behind its bumps, a map obstacle drawn where it is not). They are new, however near a believed surface.
        believed: self._obstacles('believed'); nearest: fusion.nearest_surfaces of them, when known.
        With `uncertainty`, not a return within IN_FRONT plus its slack of a mapped surface: placed from a pose that
        is off, a mapped wall's return lies up to its slack beside the wall, and along a grazing beam that is
        metres in front of it (the slack over the sine of the incidence), so the test is the return's distance
        from the mapped surface, not along its beam."""
        out = np.zeros(len(points), dtype=bool)
        if not len(believed) or not len(points):
            return out
        if nearest is None:
            nearest = nearest_surfaces(scan, pose, believed, directions)
        margin = max(IN_FRONT, 4.0 * self.spec.noise)
        out = scan.ranges[beams] < nearest[beams] - margin
        if uncertainty is not None and out.any():
            slack = uncertainty.slack(scan.ranges[beams[out]])
            out[out] = ~explained_within(points[out], self._obstacles('map'), margin + slack, END_SLACK + slack)
        return out

    def _came_into_free_space(self, points: FloatArray, centres: FloatArray, radii: FloatArray) -> NDArray[np.bool_]:
        """For each track (centres (k, 2), radii (k,)): do MOVER_FREE_POINTS of this scan's points on it (within
        EXPLAINED of its circle) lie where earlier scans saw free space, FREE_MARGIN from its edge?"""
        out = np.zeros(len(centres), dtype=bool)
        if not len(points) or not self.recent.scans:
            return out
        gap = np.hypot(points[:, None, 0] - centres[:, 0], points[:, None, 1] - centres[:, 1]) - radii   # (n, k)
        on = np.abs(gap) < EXPLAINED
        near = on.any(axis=1)
        if not near.any():
            return out
        free = np.zeros(len(points), dtype=bool)
        free[near] = self.recent.seen().covers(points[near], FREE_MARGIN)
        counts: NDArray[np.int64] = (on & free[:, None]).sum(axis=0)
        return counts >= MOVER_FREE_POINTS

    def _standing_circle(self, track_id: int, state: FloatArray, radius: float) -> Circle:
        """The still circle of a track: the one it stood as in the world, when it is still about there."""
        circle = self.standing.pop(track_id, None)
        if circle is not None and math.dist(circle.center, (state[0], state[1])) <= STANDING_SHIFT and \
                abs(circle.radius - radius) <= STANDING_SHIFT:
            return circle
        return Circle((float(state[0]), float(state[1])), radius)

    def _update_standing(self) -> bool:
        """The circles of the confirmed tracks not (yet) found moving, in the world as still obstacles (a thing
        seen is an obstacle from its third scan on, not once it has stood STILL_TIME); a track found moving leaves
        the world for the movers, one that died unseen stays, as a still obstacle, until beams show its place
        free. A standing circle follows its track, where a scan sees it, only once it is STANDING_SHIFT off (the
        world changes, and planners replan, only then). True when the world's circles changed."""
        tracker = self.tracker
        changed = False
        alive = {int(i): k for k, i in enumerate(tracker.ids)}
        for track_id in list(self.standing):
            k = alive.get(track_id)
            if k is None:        # not seen for MAX_COAST: kept, until beams show its place free
                self.seen_items.append(self.standing.pop(track_id))
            elif tracker.moved[k]:
                del self.standing[track_id]
                changed = True
        # Only where a scan saw it: a track coasting unseen is predicted, not seen, and a standing one that died
        # stays where it was last seen.
        for index in np.flatnonzero(tracker.confirmed & ~tracker.moved & (tracker.seen == tracker.time)):
            k = int(index)
            track_id = int(tracker.ids[k])
            circle = self.standing.get(track_id)
            state, radius = tracker.states[k], float(tracker.radii[k])
            if circle is None or math.dist(circle.center, (state[0], state[1])) > STANDING_SHIFT or \
                    abs(circle.radius - radius) > STANDING_SHIFT:
                self.standing[track_id] = Circle((float(state[0]), float(state[1])), radius)
                changed = True
        return changed

    def _obstacles(self, which: str) -> Obstacles:
        """The believed obstacles from the map ('map'), from the scans ('seen') or both ('believed'; not the
        standing tracks' circles, which the tracker keeps), as Obstacles, made again only when they changed."""
        if which == 'believed' and not self.map_items:
            return self._obstacles('seen')     # the same items: one Obstacles
        items = (self.map_items if which == 'map' else self.seen_items if which == 'seen' else
                 self.map_items + self.seen_items)
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
        moving = tracker.confirmed & tracker.moved & \
            (np.hypot(tracker.states[:, 2], tracker.states[:, 3]) >= STILL_SPEED)
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

    def _add_walls(self, starts: FloatArray, ends: FloatArray) -> None:
        """Believe in this scan's wall pieces: each extends a collinear believed wall it continues, else is added.
        The believed walls' ends are gathered once (a table kept up to date as pieces extend or join them), and
        which of them each piece may continue (_wall_candidates) found for all pieces at once; the walls a piece
        before extended or added since by _may_continue, the same test on one wall in floats."""
        walls = [(k, item) for k, item in enumerate(self.seen_items) if isinstance(item, Segment)]
        index = [k for k, _ in walls]
        table: FloatArray = np.array([(item.start, item.end) for _, item in walls], dtype=np.float64).reshape(-1, 2, 2)
        pieces = np.stack([starts, ends], axis=1)
        maybe = self._wall_candidates(pieces, table)
        stale: set[int] = set()     # rows changed or added since `maybe`
        for new, candidates in zip(pieces, maybe):
            rows = np.flatnonzero(candidates).tolist()
            if stale:
                piece = new.tolist()
                rows = sorted({row for row in rows if row not in stale} |
                              {row for row in stale if self._may_continue(piece, table[row].tolist())})
            for row in rows:
                a, b = table[row, 0], table[row, 1]
                run = b - a
                length = math.hypot(run[0], run[1])
                if length <= 0.0:
                    continue
                unit = run / length
                offset = new - a
                off_line = np.abs(unit[0] * offset[:, 1] - unit[1] * offset[:, 0])
                along = offset @ unit
                if off_line.max() > MERGE_TOLERANCE or along.max() < -MERGE_GAP or \
                        along.min() > length + MERGE_GAP:
                    continue
                low, high = min(0.0, float(along.min())), max(length, float(along.max()))
                p, q = a + low * unit, a + high * unit
                self.seen_items[index[row]] = Segment((float(p[0]), float(p[1])), (float(q[0]), float(q[1])))
                table[row] = (p, q)
                stale.add(row)
                break
            else:
                self.seen_items.append(Segment((float(new[0, 0]), float(new[0, 1])),
                                               (float(new[1, 0]), float(new[1, 1]))))
                index.append(len(self.seen_items) - 1)
                stale.add(len(table))
                table = np.concatenate([table, new[None]])

    @staticmethod
    def _may_continue(piece: list[list[float]], wall: list[list[float]]) -> bool:
        """_wall_candidates for one piece and one wall ((start, end) each), in Python floats: its unit vector and
        distances off the line are the exact test's own operations; along the wall a sum of two products where
        the exact test has a dot product (which may round differently: MERGE_MARGIN covers it)."""
        (ax, ay), (bx, by) = wall
        rx, ry = bx - ax, by - ay
        length = math.hypot(rx, ry)
        if length <= 0.0:
            return False     # the exact test skips such a wall
        ux, uy = rx / length, ry / length
        (px, py), (qx, qy) = piece
        off_p, off_q = abs(ux * (py - ay) - uy * (px - ax)), abs(ux * (qy - ay) - uy * (qx - ax))
        along_p, along_q = ux * (px - ax) + uy * (py - ay), ux * (qx - ax) + uy * (qy - ay)
        margin = MERGE_GAP + MERGE_MARGIN
        if math.isnan(off_p) or math.isnan(off_q) or math.isnan(along_p) or math.isnan(along_q):
            return True      # as _wall_candidates: a nan lets a wall through
        return not (max(off_p, off_q) > MERGE_TOLERANCE + MERGE_MARGIN or max(along_p, along_q) < -margin or
                    min(along_p, along_q) > length + margin)

    @staticmethod
    def _wall_candidates(pieces: FloatArray, table: FloatArray) -> NDArray[np.bool_]:
        """Which believed walls of the table (w, 2, 2) each of the pieces (p, 2, 2) may continue (p, w): _add_walls'
        test for all at once, with a margin of MERGE_MARGIN that only lets more through, so that its exact test (one
        wall at a time) runs on these few and gives the same answer as on all of them."""
        if not len(table) or not len(pieces):
            return np.zeros((len(pieces), len(table)), dtype=bool)
        a = table[:, 0]
        run = table[:, 1] - a
        length = np.hypot(run[:, 0], run[:, 1])
        unit = run / np.where(length > 0.0, length, 1.0)[:, None]
        offset = pieces[:, None, :, :] - a[None, :, None, :]                                     # (p, w, 2, 2)
        off_line = np.abs(unit[None, :, None, 0] * offset[..., 1] - unit[None, :, None, 1] * offset[..., 0])
        along = unit[None, :, None, 0] * offset[..., 0] + unit[None, :, None, 1] * offset[..., 1]
        # Negated as _add_walls' test is, so that a nan lets a wall through here as it does there.
        margin = MERGE_GAP + MERGE_MARGIN
        maybe: NDArray[np.bool_] = ~((off_line.max(axis=2) > MERGE_TOLERANCE + MERGE_MARGIN) |
                                     (along.max(axis=2) < -margin) | (along.min(axis=2) > length + margin))
        return maybe
