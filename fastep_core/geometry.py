"""Obstacle geometry: circles and line segments, vectorised over many query points.

Line obstacles use the paper's "minimum distance technique": the distance from a point p to segment a-b is
|p - (a + t (b - a))| with t = clip(((p - a).(b - a)) / |b - a|^2, 0, 1). All distances here are to the
obstacle *surface* (a circle's centre distance minus its radius), so "clearance < r" means "a disc of radius
r at that point touches the obstacle".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    'Circle', 'Segment', 'Obstacle', 'Obstacles',
    'norm', 'point_segment_distance', 'segment_segment_distance',
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Circle:
    """A disc obstacle."""

    center: tuple[float, float]
    radius: float


@dataclass(frozen=True)
class Segment:
    """A line (wall) obstacle of zero thickness."""

    start: tuple[float, float]
    end: tuple[float, float]


Obstacle = Circle | Segment


def norm(dx: FloatArray, dy: FloatArray) -> FloatArray:
    """sqrt(dx^2 + dy^2): five times faster than np.hypot, and map-sized values cannot overflow."""
    return np.sqrt(dx * dx + dy * dy)


def point_segment_distance(p: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distance from points p to segments a-b, broadcasting over leading axes (last axis is x, y)."""
    px, py = p[..., 0], p[..., 1]
    ax, ay = a[..., 0], a[..., 1]
    abx, aby = b[..., 0] - ax, b[..., 1] - ay
    denom = abx * abx + aby * aby
    t = ((px - ax) * abx + (py - ay) * aby) / np.where(denom > 0.0, denom, 1.0)
    t = np.minimum(np.maximum(t, 0.0), 1.0)
    return norm(px - ax - t * abx, py - ay - t * aby)


def _cross(u: FloatArray, v: FloatArray) -> FloatArray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


PARALLEL = 1e-9
"""segment_segment_distance: segments whose angle has a sine at most this are parallel (they do not cross)."""


def segment_segment_distance(p0: FloatArray, p1: FloatArray, q0: FloatArray, q1: FloatArray) -> FloatArray:
    """Minimum distance between segments p0-p1 and q0-q1 (0 where they cross), broadcasting."""
    d = np.minimum(
        np.minimum(point_segment_distance(p0, q0, q1), point_segment_distance(p1, q0, q1)),
        np.minimum(point_segment_distance(q0, p0, p1), point_segment_distance(q1, p0, p1)),
    )
    r, s = p1 - p0, q1 - q0
    # Proper crossing: the endpoints of each segment lie strictly on opposite sides of the other, and the segments
    # are not parallel. On (nearly) collinear segments the four cross products are rounding noise whose signs say
    # nothing: two collinear segments a metre apart came out crossing, distance 0. Segments that cross that close
    # to parallel (sin of the angle <= PARALLEL) have an endpoint within PARALLEL x their length of the other,
    # which d measures.
    o1, o2 = _cross(r, q0 - p0), _cross(r, q1 - p0)
    o3, o4 = _cross(s, p0 - q0), _cross(s, p1 - q0)
    turn = _cross(r, s)
    crossing = (o1 * o2 < 0.0) & (o3 * o4 < 0.0) & \
        (turn * turn > PARALLEL * PARALLEL * np.sum(r * r, axis=-1) * np.sum(s * s, axis=-1))
    return np.where(crossing, 0.0, d)


class Obstacles:
    """A fixed set of circle and segment obstacles stored as arrays for vectorised queries."""

    def __init__(self, obstacles: Iterable[Obstacle] = ()) -> None:
        items = tuple(obstacles)
        circles = [o for o in items if isinstance(o, Circle)]
        segments = [o for o in items if isinstance(o, Segment)]
        self.items: tuple[Obstacle, ...] = tuple(circles) + tuple(segments)
        self.centers: FloatArray = np.array([c.center for c in circles], dtype=float).reshape(-1, 2)
        self.radii: FloatArray = np.array([c.radius for c in circles], dtype=float)
        self.starts: FloatArray = np.array([s.start for s in segments], dtype=float).reshape(-1, 2)
        self.ends: FloatArray = np.array([s.end for s in segments], dtype=float).reshape(-1, 2)
        # Per-segment constants of the point-segment distance, hoisted out of the swarm's hot loop.
        self._ab = self.ends - self.starts
        length2 = np.einsum('ij,ij->i', self._ab, self._ab)
        self._inv_length2 = np.where(length2 > 0.0, 1.0 / np.where(length2 > 0.0, length2, 1.0), 0.0)
        # fan_clearance's points: the circles' centres, the walls' starts, the walls' ends.
        self._fan_points = np.concatenate([self.centers, self.starts, self.ends])
        self._walls_of_point: tuple[FloatArray, ...] | None = None   # made by _from_point when first needed

    def __len__(self) -> int:
        return len(self.items)

    def subset(self, keep: NDArray[np.bool_]) -> Obstacles:
        """The obstacles where `keep` (one bool per obstacle, circles first) is true."""
        return Obstacles(item for item, k in zip(self.items, keep) if k)

    @property
    def n_circles(self) -> int:
        return len(self.radii)

    def distances(self, points: ArrayLike) -> FloatArray:
        """Surface distance from each point to each obstacle: shape (..., n_obstacles), circles first."""
        p = np.asarray(points, dtype=float)[..., None, :]
        circ = norm(p[..., 0] - self.centers[:, 0], p[..., 1] - self.centers[:, 1]) - self.radii
        if not len(self.starts):
            return circ
        ax, ay = p[..., 0] - self.starts[:, 0], p[..., 1] - self.starts[:, 1]
        abx, aby = self._ab[:, 0], self._ab[:, 1]
        t = np.minimum(np.maximum((ax * abx + ay * aby) * self._inv_length2, 0.0), 1.0)
        seg = norm(ax - t * abx, ay - t * aby)
        return np.concatenate([circ, seg], axis=-1)

    def distance_rows(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """distances() transposed: shape (n_obstacles, m) for m points given as coordinate arrays.

        Each row is contiguous, so sums and minima over obstacles run along long rows; for the swarm's
        ~1,200 candidates this is about twice as fast as the (m, n_obstacles) layout.
        """
        cx, cy = self.centers[:, 0, None], self.centers[:, 1, None]
        circ = norm(x - cx, y - cy) - self.radii[:, None]
        if not len(self.starts):
            return circ
        return np.concatenate([circ, self._wall_rows(x, y)], axis=0)

    def _from_point(self, p: FloatArray) -> FloatArray:
        """point_segment_distance(p, starts, ends) for one point p: the same operations, with what depends on
        the walls alone computed once."""
        walls = self._walls_of_point
        if walls is None:
            sx, sy = self.starts[..., 0], self.starts[..., 1]
            abx, aby = self.ends[..., 0] - sx, self.ends[..., 1] - sy
            denom = abx * abx + aby * aby
            walls = self._walls_of_point = (sx, sy, abx, aby, np.where(denom > 0.0, denom, 1.0))
        sx, sy, abx, aby, denom = walls
        qx, qy = p[..., 0] - sx, p[..., 1] - sy
        t = (qx * abx + qy * aby) / denom
        t = np.minimum(np.maximum(t, 0.0), 1.0)
        return norm(qx - t * abx, qy - t * aby)

    def _wall_rows(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """The walls' rows of distance_rows: shape (n_segments, m)."""
        ax, ay = x - self.starts[:, 0, None], y - self.starts[:, 1, None]
        abx, aby = self._ab[:, 0, None], self._ab[:, 1, None]
        t = np.minimum(np.maximum((ax * abx + ay * aby) * self._inv_length2[:, None], 0.0), 1.0)
        rows: FloatArray = norm(ax - t * abx, ay - t * aby)
        return rows

    def clearance(self, points: ArrayLike) -> FloatArray:
        """Distance from each point to the nearest obstacle surface (inf when there are none)."""
        d = self.distances(points)
        if d.shape[-1] == 0:
            return np.full(d.shape[:-1], np.inf)
        nearest: FloatArray = d.min(axis=-1)
        return nearest

    def _boxes(self) -> tuple[FloatArray, FloatArray, float, bool]:
        """Each obstacle's bounding box (lows (n, 2), highs (n, 2), circles first), a rounding margin for tests
        against them (metres, relative to the coordinates' size) and whether every obstacle is finite; cached."""
        cached: tuple[FloatArray, FloatArray, float, bool] | None = getattr(self, '_box_cache', None)
        if cached is None:
            size = np.abs(self.radii)[:, None]
            lows = np.concatenate([self.centers - size, np.minimum(self.starts, self.ends)])
            highs = np.concatenate([self.centers + size, np.maximum(self.starts, self.ends)])
            finite = bool(np.isfinite(lows).all() and np.isfinite(highs).all())
            scale = float(np.abs(np.concatenate([lows, highs])).max(initial=0.0)) if finite else 0.0
            cached = lows, highs, 1e-6 * (1.0 + scale), finite
            self._box_cache = cached
        return cached

    @property
    def scale(self) -> float:
        """The largest absolute coordinate of any obstacle's bounding box (0 with none, inf when one is not
        finite): what rounding margins of distances to them are relative to."""
        scale: float | None = getattr(self, '_scale', None)
        if scale is None:
            lows, highs, _, finite = self._boxes()
            scale = float(np.abs(np.concatenate([lows, highs])).max(initial=0.0)) if finite else math.inf
            self._scale = scale
        return scale

    def near(self, points: ArrayLike, within: float, end_slack: float | FloatArray | None = None) -> NDArray[np.bool_]:
        """clearance(points) < within for points (m, 2), the same answer bit for bit, without the m x n matrix of
        distances: only the (point, obstacle) pairs where the point lies in the obstacle's bounding box grown by
        `within` (and a rounding margin) can be that close, and only their distances are computed, each with the
        same arithmetic as distances(). Points sorted by x find each obstacle's candidates by binary search.

        end_slack: a segment counts only for the points whose foot on its line lies within the segment or at most
        this far beyond an end (None: any, as clearance counts them; one per segment, +inf for any, or for all)."""
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        out = np.zeros(len(p), dtype=bool)
        if not len(p) or not len(self):
            return out
        lows, highs, margin, finite = self._boxes()
        if not (finite and math.isfinite(within)):
            near: NDArray[np.bool_] = self.clearance(p) < within
            return near
        grow = max(within, 0.0) + margin
        order = np.argsort(p[:, 0], kind='stable')
        xs = p[order, 0]
        first = np.searchsorted(xs, lows[:, 0] - grow, 'left')
        counts = np.searchsorted(xs, highs[:, 0] + grow, 'right') - first
        owner = np.repeat(np.arange(len(self)), counts)
        offsets = np.cumsum(counts) - counts
        point = order[np.arange(len(owner)) + np.repeat(first - offsets, counts)]
        y = p[point, 1]
        keep = (y >= lows[owner, 1] - grow) & (y <= highs[owner, 1] + grow)
        owner, point = owner[keep], point[keep]
        split = int(np.searchsorted(owner, self.n_circles))                 # circles' pairs first
        pc, c = p[point[:split]], owner[:split]
        circle = norm(pc[:, 0] - self.centers[c, 0], pc[:, 1] - self.centers[c, 1]) - self.radii[c]
        ps, k = p[point[split:]], owner[split:] - self.n_circles
        ax, ay = ps[:, 0] - self.starts[k, 0], ps[:, 1] - self.starts[k, 1]
        abx, aby = self._ab[k, 0], self._ab[k, 1]
        along = (ax * abx + ay * aby) * self._inv_length2[k]
        t = np.minimum(np.maximum(along, 0.0), 1.0)
        segment = norm(ax - t * abx, ay - t * aby)
        if end_slack is not None:   # beyond an end by more than the slack: not this segment's point
            with np.errstate(invalid='ignore'):   # +inf times a point-segment's 0: nan, which bounds nothing either
                slack = (end_slack if np.ndim(end_slack) == 0 else np.asarray(end_slack)[k]) * \
                    np.sqrt(self._inv_length2[k])
            segment = np.where((along < -slack) | (along > 1.0 + slack), np.inf, segment)
        out[point[np.concatenate([circle, segment]) < within]] = True
        return out

    def path_distances(self, a: ArrayLike, b: ArrayLike) -> FloatArray:
        """Minimum distance from straight runs a-b to each obstacle surface: shape (..., n_obstacles)."""
        a = np.asarray(a, dtype=float)[..., None, :]
        b = np.asarray(b, dtype=float)[..., None, :]
        circ = point_segment_distance(self.centers, a, b) - self.radii
        if not len(self.starts):
            return circ
        seg = segment_segment_distance(a, b, self.starts, self.ends)
        return np.concatenate([circ, seg], axis=-1)

    def path_clearance(self, a: ArrayLike, b: ArrayLike) -> FloatArray:
        """Closest approach of the straight runs a-b to any obstacle surface (inf when there are none)."""
        d = self.path_distances(a, b)
        if d.shape[-1] == 0:
            return np.full(d.shape[:-1], np.inf)
        nearest: FloatArray = d.min(axis=-1)
        return nearest

    def fan_clearance(self, origin: ArrayLike, ends: ArrayLike) -> FloatArray:
        """path_clearance(origin, ends) for one origin and many ends (m, 2): the swarm's hot path.

        Same result as path_clearance, computed in the (n_obstacles, m) layout of distance_rows with the
        origin's own distance to each segment computed once, and the distances of the circles' centres and
        the walls' ends to every run in one array.
        """
        o = np.asarray(origin, dtype=float)
        X = np.asarray(ends, dtype=float)
        dx, dy = X[:, 0] - o[0], X[:, 1] - o[1]
        inv_length2 = 1.0 / np.maximum(dx * dx + dy * dy, 1e-300)
        if not len(self):
            return np.full(len(X), np.inf)
        # Distance from each point (circle centres, wall starts, wall ends; relative to the origin) to each run.
        rel = self._fan_points - o
        qx, qy = rel[:, 0, None], rel[:, 1, None]
        t = np.minimum(np.maximum((qx * dx + qy * dy) * inv_length2, 0.0), 1.0)
        to_run = norm(qx - t * dx, qy - t * dy)
        nc, nw = self.n_circles, len(self.starts)
        out: FloatArray = (to_run[:nc] - self.radii[:, None]).min(axis=0) if nc else np.full(len(X), np.inf)
        if nw:
            sx, sy, ex, ey = qx[nc:nc + nw], qy[nc:nc + nw], qx[nc + nw:], qy[nc + nw:]
            wall = self._wall_rows(X[:, 0], X[:, 1])                                 # run ends to each wall
            from_origin = self._from_point(o)[:, None]
            d = np.minimum(np.minimum(wall, from_origin), np.minimum(to_run[nc:nc + nw], to_run[nc + nw:]))
            wx, wy = ex - sx, ey - sy
            crossing = ((dx * sy - dy * sx) * (dx * ey - dy * ex) < 0.0) & \
                ((wy * sx - wx * sy) * (wx * (dy - sy) - wy * (dx - sx)) < 0.0)
            out = np.minimum(out, np.where(crossing, 0.0, d).min(axis=0))
        return out

    def blocking(self, a: ArrayLike, b: ArrayLike, within: float) -> NDArray[np.bool_]:
        """Which obstacles the straight run a-b passes within `within` of (one bool per obstacle)."""
        return self.path_distances(a, b) < within
