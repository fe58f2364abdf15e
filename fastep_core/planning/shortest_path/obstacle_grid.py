"""A spatial index for the exact shortest path (planning/shortest_path/optimal.py): which obstacles lie near a straight
edge.

The visibility graph has about 2 N^2 candidate edges among N obstacles; measuring each against every obstacle
at once took O(N^3) memory (500 circles: 9.4 GB). ObstacleGrid bins the obstacles in square cells and measures
an edge only against those listed where it passes, with the same formulas, so every decision is the same.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Obstacles, point_segment_distance, segment_segment_distance

__all__ = ['ObstacleGrid']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
PAIRS_PER_BLOCK = 1 << 19
"""Edge-obstacle pairs measured at once: the blocks' arrays stay within some tens of MB, whatever the world."""
DIRECT_PAIRS = 4096
"""Up to this many edge-obstacle pairs, `free` measures every pair at once instead of looking them up: the
lookup's few dozen numpy calls cost more than measuring them all (a typical call: 2 edges, 5-30 obstacles)."""


class ObstacleGrid:
    """The obstacles binned in square cells, so that an edge is measured against the obstacles near it only.

    Why: measuring every candidate edge (about 2 N^2 of them) against every obstacle at once took O(N^3)
    memory (500 circles: 9.4 GB). Here an obstacle is listed in every cell its reach square overlaps: its
    bounding box grown by the threshold, half the sample spacing and a rounding slack. An edge is sampled at
    most one cell size apart, ends included; an obstacle closer to the edge than the threshold is then
    closer than that (in every coordinate) to one of the samples, so it is listed in that sample's cell. The
    pairs found are measured with the same formulas as `Obstacles.path_distances` (so the decision is the
    same, bit for bit); an edge is free when none of them is below the threshold. The midpoints go first:
    in a cluttered world most candidate edges are blocked there, and never sampled in full.
    """

    def __init__(self, obstacles: Obstacles, box: tuple[float, float, float, float], threshold: float,
                 scale: float) -> None:
        self.obstacles = obstacles
        self.threshold = threshold
        self.n_circles = obstacles.n_circles
        self.usable = False
        x0, y0, x1, y1 = box
        n = len(obstacles)
        if n == 0:
            return
        width, height = x1 - x0, y1 - y0
        slack = 1e-6 + 1e-9 * scale
        # Low and high corners of each obstacle's bounding box: circles, then segments.
        o = obstacles
        lo = np.concatenate([o.centers - o.radii[:, None], np.minimum(o.starts, o.ends)])
        hi = np.concatenate([o.centers + o.radii[:, None], np.maximum(o.starts, o.ends)])
        # About one cell per obstacle; coarser while the listings would exceed 16 per obstacle (big obstacles).
        cell = math.sqrt(max(width, 0.0)) * math.sqrt(max(height, 0.0)) / math.sqrt(n)
        cell = max(cell, (width + height) / 4096.0, 1e-9 * (1.0 + scale), threshold)
        for _ in range(64):
            if not (math.isfinite(cell) and cell > 0.0):
                return
            grow = threshold + 0.5 * cell + slack
            nx = max(1, min(4096, int(math.ceil(width / cell))))
            ny = max(1, min(4096, int(math.ceil(height / cell))))
            with np.errstate(invalid='ignore', over='ignore'):
                ix0 = np.floor((lo[:, 0] - grow - x0) / cell)
                ix1 = np.floor((hi[:, 0] + grow - x0) / cell)
                iy0 = np.floor((lo[:, 1] - grow - y0) / cell)
                iy1 = np.floor((hi[:, 1] + grow - y0) / cell)
            spans = np.stack([ix0, ix1, iy0, iy1])
            if not np.all(np.isfinite(spans)):
                return
            ix0, ix1 = np.clip(ix0, 0, nx - 1), np.clip(ix1, -1, nx - 1)
            iy0, iy1 = np.clip(iy0, 0, ny - 1), np.clip(iy1, -1, ny - 1)
            cols = np.maximum(ix1 - ix0 + 1, 0).astype(np.int64)
            rows = np.maximum(iy1 - iy0 + 1, 0).astype(np.int64)
            counts = cols * rows
            if int(counts.sum()) <= 16 * n + 4096 or (nx == 1 and ny == 1):
                break
            cell *= 2.0
        else:
            return
        # (cell, obstacle) listings, sorted by cell: cell c lists members[first[c]:first[c + 1]].
        owner = np.repeat(np.arange(n), counts)
        k = np.arange(len(owner)) - np.repeat(np.cumsum(counts) - counts, counts)
        ix = ix0.astype(np.int64)[owner] + k % np.maximum(cols, 1)[owner]
        iy = iy0.astype(np.int64)[owner] + k // np.maximum(cols, 1)[owner]
        cells = iy * nx + ix
        order = np.argsort(cells, kind='stable')
        self.members = owner[order]
        self.first = np.concatenate([[0], np.cumsum(np.bincount(cells, minlength=nx * ny))])
        self.origin, self.cell, self.nx, self.ny = (x0, y0), cell, nx, ny
        self.usable = True

    def free(self, P: FloatArray, Q: FloatArray) -> NDArray[np.bool_]:
        """Which edges P[i]-Q[i] keep at least the threshold from every obstacle."""
        blocked = np.zeros(len(P), dtype=bool)
        if not self.usable or len(P) * len(self.obstacles) <= DIRECT_PAIRS:
            # Rounding or overflow makes the grid useless (absurd coordinates), or there are few pairs: every
            # pair, in blocks. The pairs the grid leaves out are farther than the threshold: same decisions.
            n = len(self.obstacles)
            step = max(1, PAIRS_PER_BLOCK // max(n, 1))
            for a in range(0, len(P), step):
                e = np.repeat(np.arange(a, min(a + step, len(P))), n)
                self._measure(P, Q, e, np.tile(np.arange(n), len(e) // n), blocked)
            return ~blocked
        mid = 0.5 * (P + Q)
        self._sampled(P, Q, np.arange(len(P)), mid, blocked)
        alive = np.flatnonzero(~blocked)
        if len(alive):
            lengths = np.hypot(*(Q[alive] - P[alive]).T)
            with np.errstate(invalid='ignore', over='ignore'):
                n_samples = np.ceil(lengths / self.cell)
            n_samples = np.where(np.isfinite(n_samples), n_samples, 0.0)
            n_samples = (np.minimum(n_samples, 2.0 * (self.nx + self.ny)) + 1).astype(np.int64)
            # Blocks of edges whose samples (about 8 listed obstacles each) stay within a block of pairs.
            ends = np.cumsum(n_samples)
            block = max(1, PAIRS_PER_BLOCK // 8)
            a = 0
            while a < len(alive):
                b = max(a + 1, int(np.searchsorted(ends, ends[a] - n_samples[a] + block, side='right')))
                edges, counts = alive[a:b], n_samples[a:b]
                e = np.repeat(edges, counts)
                k = np.arange(len(e)) - np.repeat(np.cumsum(counts) - counts, counts)
                t = (k / np.maximum(np.repeat(counts, counts) - 1, 1))[:, None]
                points = P[e] + t * (Q[e] - P[e])
                self._sampled(P, Q, e, points, blocked)
                a = b
        return ~blocked

    def _sampled(self, P: FloatArray, Q: FloatArray, edge: IntArray, points: FloatArray,
                 blocked: NDArray[np.bool_]) -> None:
        """Measure edge[i] against the obstacles listed in the cell of points[i], in blocks of pairs."""
        x0, y0 = self.origin
        ix = np.clip(np.floor((points[:, 0] - x0) / self.cell), 0, self.nx - 1).astype(np.int64)
        iy = np.clip(np.floor((points[:, 1] - y0) / self.cell), 0, self.ny - 1).astype(np.int64)
        cells = iy * self.nx + ix
        start = self.first[cells]
        counts = self.first[cells + 1] - start
        ends = np.cumsum(counts)
        a = 0
        while a < len(edge):
            b = max(a + 1, int(np.searchsorted(ends, ends[a] - counts[a] + PAIRS_PER_BLOCK, side='right')))
            c = counts[a:b]
            e = np.repeat(edge[a:b], c)
            k = np.arange(len(e)) - np.repeat(np.cumsum(c) - c, c)
            self._measure(P, Q, e, self.members[np.repeat(start[a:b], c) + k], blocked)
            a = b

    def _measure(self, P: FloatArray, Q: FloatArray, e: IntArray, o: IntArray,
                 blocked: NDArray[np.bool_]) -> None:
        """Mark edge e[i] blocked when obstacle o[i] is nearer than the threshold (or the distance is NaN)."""
        obstacles = self.obstacles
        circle = o < self.n_circles
        ec, oc = e[circle], o[circle]
        if len(ec):
            d = point_segment_distance(obstacles.centers[oc], P[ec], Q[ec]) - obstacles.radii[oc]
            blocked[ec[~(d >= self.threshold)]] = True
        es, os_ = e[~circle], o[~circle] - self.n_circles
        if len(es):
            d = segment_segment_distance(P[es], Q[es], obstacles.starts[os_], obstacles.ends[os_])
            blocked[es[~(d >= self.threshold)]] = True
