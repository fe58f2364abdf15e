"""Shapes of scan clusters: a circle fitted to each cluster at once, and straight walls for those no circle fits.

Circles: the algebraic least-squares fit of Kasa (1976, IEEE Trans. Instrum. Meas. 25): minimise
sum (x^2 + y^2 + D x + E y + F)^2 over D, E, F, a 3 x 3 linear system per cluster, all clusters' sums from one
np.bincount (cluster_sums) and the systems solved together; centre (-D/2, -E/2), radius sqrt(cx^2 + cy^2 - F).
A circle needs MIN_CIRCLE_POINTS points, an RMS residual within the noise plus CIRCLE_RESIDUAL, a radius of at
most MAX_CIRCLE_RADIUS, an arc of 60 degrees or more (a few points at the edge of the range fit any circle), its
centre beyond the points as the scanner sees them, and no beam of the scan through the disc (a slightly bent wall
fits a circle of metres reaching into space the scan shows free). Walls: every other cluster of MIN_POINTS points
within `wall_range` becomes a Douglas-Peucker polyline (tolerance WALL_TOLERANCE or 3 noise sigmas), each piece
moved to its nearest return, both ends extended by the gap between beams there (extend_ends). Farther clusters
wait: a circle entering the range shows its nearest points first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import NDArray

__all__ = ['CIRCLE_RESIDUAL', 'MAX_CIRCLE_RADIUS', 'MIN_ARC', 'MIN_CIRCLE_POINTS', 'MIN_POINTS', 'WALL_TOLERANCE',
           'Shapes', 'cluster_sums', 'extend_ends', 'fit_circles', 'polyline', 'shapes']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

MIN_POINTS = 3
"""Clusters of fewer points are left out (a lone return: noise, or an object that more beams will show soon)."""
MIN_CIRCLE_POINTS = 5
MIN_ARC = 1.0
"""Chord / radius a circle's points must span (1: 60 degrees of arc)."""
CIRCLE_RESIDUAL = 0.02
"""Metres added to 2 x the scan noise: the RMS residual a circle fit may have."""
MAX_CIRCLE_RADIUS = 4.0
"""Metres: larger fits are walls (a straight wall fits a huge circle)."""
WALL_TOLERANCE = 0.1
"""Metres (or 3 noise sigmas, if more): Douglas-Peucker tolerance of walls (each piece then moved toward the
scanner to its nearest return: _in_front_of)."""


@dataclass(frozen=True)
class Shapes:
    """What one scan's clusters are: circles (centres (c, 2), radii (c,)) and wall segments (starts, ends (s, 2))."""

    centres: FloatArray
    radii: FloatArray
    starts: FloatArray
    ends: FloatArray


def cluster_sums(labels: IntArray, weights: FloatArray, n_clusters: int) -> FloatArray:
    """Each row of weights (w, n) summed per cluster (w, n_clusters): np.bincount(labels, weights=row) of every
    row from one bincount call (each bin's sum taken in the points' order, as bincount of the row alone does)."""
    rows = len(weights)
    keys = (labels[None, :] + n_clusters * np.arange(rows)[:, None]).ravel()
    sums: FloatArray = np.bincount(keys, weights=weights.ravel(), minlength=rows * n_clusters).astype(float, copy=False)
    return sums.reshape(rows, n_clusters)


def fit_circles(points: FloatArray, labels: IntArray, n_clusters: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Kasa fits of every cluster: centres (k, 2), radii (k,) and RMS residuals (k,); nan where singular."""
    n: FloatArray = np.bincount(labels, minlength=n_clusters).astype(float)
    # Each cluster about its own mean: the normal equations stay well conditioned far from the map's origin.
    mean = cluster_sums(labels, points.T, n_clusters).T / np.maximum(n, 1.0)[:, None]
    local = points - mean[labels]
    x, y = local[:, 0], local[:, 1]
    z = x * x + y * y
    sx, sy, sxx, syy, sxy, sz, sxz, syz = cluster_sums(labels, np.stack([x, y, x * x, y * y, x * y, z, x * z, y * z]),
                                                       n_clusters)
    # Normal equations of min sum (z + D x + E y + F)^2: A [D, E, F] = -[sxz, syz, sz].
    a = np.stack([sxx, sxy, sx, sxy, syy, sy, sx, sy, n], -1).reshape(-1, 3, 3)
    b = -np.stack([sxz, syz, sz], -1)
    ok = np.abs(np.linalg.det(a)) > 1e-12 * np.maximum(n, 1.0) ** 3
    solution = np.full((n_clusters, 3), np.nan)
    if ok.any():
        solution[ok] = np.linalg.solve(a[ok], b[ok][..., None])[..., 0]
    centres = -0.5 * solution[:, :2]
    radii = np.sqrt(np.maximum((centres ** 2).sum(axis=1) - solution[:, 2], 0.0))
    radial = np.hypot(x - centres[labels, 0], y - centres[labels, 1]) - radii[labels]
    squares = np.where(np.isnan(radial), np.inf, radial ** 2)
    rms = np.sqrt(np.bincount(labels, weights=squares, minlength=n_clusters) / np.maximum(n, 1.0))   # singular: inf
    return centres + mean, radii, rms


def _spans(points: FloatArray, labels: IntArray, n_clusters: int) -> FloatArray:
    """Each cluster's chord: the distance between its two ends. Found as the point farthest from any point of
    it (an end of an arc), then the point farthest from that one (the other end): in any beam order, so also for
    the cluster that closes a full turn."""
    index = np.arange(len(points))
    anchor = np.zeros(n_clusters, dtype=np.int64)
    anchor[labels[::-1]] = index[::-1]                                   # one point of each cluster
    for _ in range(2):
        d = np.hypot(*(points - points[anchor[labels]]).T)
        best = np.full(n_clusters, -1.0)
        np.maximum.at(best, labels, d)
        farthest = np.zeros(n_clusters, dtype=np.int64)
        farthest[labels[d == best[labels]]] = index[d == best[labels]]
        anchor, span = farthest, best
    return span


def polyline(points: FloatArray, tolerance: float = WALL_TOLERANCE) -> list[int]:
    """Douglas-Peucker: indices of the points (in order) kept as the polyline's vertices."""
    keep = [0, len(points) - 1]
    stack = [(0, len(points) - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        a, b = points[i], points[j]
        ab = b - a
        length = float(np.hypot(*ab))
        inner = points[i + 1:j] - a
        if length > 0.0:
            d = np.abs(ab[0] * inner[:, 1] - ab[1] * inner[:, 0]) / length
        else:
            d = np.hypot(*inner.T)
        k = int(np.argmax(d))
        if d[k] > tolerance:
            keep.append(i + 1 + k)
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
    return sorted(set(keep))


def _in_front_of(points: FloatArray, first: IntArray, a: FloatArray, b: FloatArray,
                 origin: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The polylines' pieces (starts a, ends b (p, 2)) each moved toward the scanner to its nearest point: a wall
    is never believed behind a return it was fitted to (a simplified piece's chord lies up to its tolerance off its
    points, either side), so that a return in front of a believed wall is something the belief lacks. points: the
    walls' points in order, piece k's from first[k] up to first[k + 1] (each polyline's last point: its last)."""
    run = b - a
    length = np.hypot(run[:, 0], run[:, 1])
    normal = np.column_stack([-run[:, 1], run[:, 0]]) / np.where(length > 0.0, length, 1.0)[:, None]
    normal *= np.where(((origin - a) * normal).sum(axis=1) < 0.0, -1.0, 1.0)[:, None]      # toward the scanner
    piece = np.searchsorted(first, np.arange(len(points)), side='right') - 1
    ahead = np.maximum.reduceat(((points - a[piece]) * normal[piece]).sum(axis=1), first)
    shift = np.where(length > 0.0, np.maximum(ahead, 0.0), 0.0)[:, None] * normal
    return a + shift, b + shift


def extend_ends(vertices: FloatArray, first: IntArray, last: IntArray, origin: FloatArray,
                beam_gap: float) -> FloatArray:
    """Polylines (vertices (v, 2), polyline k from first[k] to last[k], two vertices or more) with both ends
    extended by the gap between beams there (beam_gap radians at the end's distance from origin): the wall goes
    on somewhere between its last return and the next beam (at 5 m and 1 degree, 9 cm), so the robot does not
    cut the true end. Each polyline's first end, then its last (of two vertices: from the first, extended)."""
    out = vertices.copy()
    for end, inner in ((first, first + 1), (last, last - 1)):
        run = out[end] - out[inner]
        length = np.hypot(run[:, 0], run[:, 1])
        grow = length > 0.0
        reach = np.hypot(out[end, 0] - origin[0], out[end, 1] - origin[1]) * beam_gap
        out[end[grow]] = out[end[grow]] + run[grow] * (reach[grow] / length[grow])[:, None]
    return out


def shapes(points: FloatArray, beams: IntArray, labels: IntArray, origin: FloatArray, noise: float = 0.0,
           wall_range: float = math.inf, beam_gap: float = 0.0,
           seen_free: Callable[[FloatArray, FloatArray], NDArray[np.bool_]] | None = None) -> Shapes:
    """Circles and walls of clustered scan points (segmentation.segment) seen from origin (module docstring).
    seen_free(centres, radii): which circles the scan itself shows free space inside (beams passing through
    the disc: a bent wall piece fits a large circle that reaches into free space); such a cluster is no circle."""
    if len(points) == 0:
        empty = np.zeros((0, 2))
        return Shapes(empty, np.zeros(0), empty, empty)
    n_clusters = int(labels.max()) + 1
    counts = np.bincount(labels, minlength=n_clusters)
    centres, radii, rms = fit_circles(points, labels, n_clusters)
    ranges = np.hypot(*(points - origin).T)
    mean_range = np.bincount(labels, weights=ranges, minlength=n_clusters) / np.maximum(counts, 1)
    nearest = np.full(n_clusters, np.inf)
    np.minimum.at(nearest, labels, ranges)
    behind = np.hypot(*(centres - origin).T) > mean_range
    chord = _spans(points, labels, n_clusters)
    circle = (counts >= MIN_CIRCLE_POINTS) & np.isfinite(radii) & (rms <= CIRCLE_RESIDUAL + 2.0 * noise) & \
        (radii <= MAX_CIRCLE_RADIUS) & (radii > 0.0) & behind & (chord >= MIN_ARC * radii)
    if seen_free is not None and circle.any():
        circle[circle] = ~seen_free(centres[circle], radii[circle])
    walls: list[FloatArray] = []      # each wall cluster's points in order, and its polyline's vertices
    vertices_of: list[FloatArray] = []
    firsts: list[IntArray] = []       # where each piece's points begin among all the walls' points
    count = 0
    for k in np.flatnonzero(~circle & (counts >= MIN_POINTS) & (nearest <= wall_range)):
        index = np.flatnonzero(labels == k)
        jumps = np.flatnonzero(np.diff(beams[index]) > 1)
        if len(jumps):   # the cluster that closes a full turn: start it after its gap in beam order
            index = np.roll(index, -(int(jumps[0]) + 1))
        ordered = points[index]
        kept = polyline(ordered, max(WALL_TOLERANCE, 3.0 * noise))
        walls.append(ordered)
        vertices_of.append(ordered[kept])
        firsts.append(count + np.asarray(kept[:-1], dtype=np.int64))
        count += len(ordered)
    if not walls:
        return Shapes(centres[circle], radii[circle], np.zeros((0, 2)), np.zeros((0, 2)))
    vertices = np.concatenate(vertices_of)
    last = np.cumsum([len(v) for v in vertices_of]) - 1            # each polyline's last vertex in `vertices`
    first = np.concatenate([[0], last[:-1] + 1])
    vertices = extend_ends(vertices, first, last, origin, beam_gap)
    inner = np.ones(len(vertices), dtype=bool)
    inner[last] = False                                             # a piece from each vertex but the last
    starts, ends = _in_front_of(np.concatenate(walls), np.concatenate(firsts), vertices[inner],
                                vertices[np.roll(inner, 1)], origin)
    return Shapes(centres[circle], radii[circle], starts, ends)
