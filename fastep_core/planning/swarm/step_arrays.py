"""The step fitness's array kernels (planning/swarm/step.py): candidates' distance rows into reused scratch arrays, and
row sums of mostly-zero arrays equal to numpy's, bit for bit.

Apart from StepProblem because they are about numpy, not about the step: how numpy sums a row (the floats the swarm
compares must not change, tests/fastep_core/planning/swarm/test_step_terms.py) and what allocating afresh costs.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Obstacles

__all__ = ['DENSE_BELOW', 'DENSE_FROM', 'DistanceRows', 'near_row_sum', 'sparse_row_sum']

FloatArray = NDArray[np.float64]
DENSE_FROM = 4
"""near_row_sum builds the whole (candidates, robots) array from this many robots in reach on ..."""
DENSE_BELOW = 256
"""... for fewer candidates than this: filling and summing the whole array grows with the candidates (15 robots:
3 us for 50 candidates, 30-45 us for an attraction call's ~1 225), adding the robots in reach does not (4-15 us)."""


class DistanceRows:
    """Distances of candidates to some points and to some of the obstacles, one row each, into scratch arrays.

    Rows: the plain distances to `points` (StepProblem: the origin, the target), then the surface distances to
    the obstacles `which` (indices, ascending: circles, then walls), each computed with the very operations of
    geometry.norm and Obstacles.distance_rows (the same floats) but all rows at once. The arrays are made once
    and reused (views of the first n * m elements, contiguous like a fresh array): with many obstacles they are
    a few hundred kB each, and allocated afresh on every call the allocator handed them back to the system and
    took them again, the page faults costing as much as the arithmetic (circle fields: ~340 against ~160 us
    per call of 1,226 candidates).
    """

    def __init__(self, points: FloatArray, obstacles: Obstacles, which: NDArray[np.int64]) -> None:
        nc = obstacles.n_circles
        circles, walls = which[which < nc], which[which >= nc] - nc
        # The points each candidate's offset (x - px, y - py) is taken from: `points`, the circles' centres
        # and the walls' starts (the minimum distance technique); the distance itself for all but the last.
        offsets = np.concatenate([points, obstacles.centers[circles], obstacles.starts[walls]])
        self.px, self.py = offsets[:, 0, None], offsets[:, 1, None]
        self.first_circle = len(points)
        self.norms = len(points) + len(circles)
        self.circle_r = obstacles.radii[circles][:, None]
        # The very constants Obstacles.distance_rows uses (the same floats give the same distances).
        self.seg_dx, self.seg_dy = obstacles._ab[walls, 0, None], obstacles._ab[walls, 1, None]
        self.seg_inv_length2 = obstacles._inv_length2[walls][:, None]
        self._capacity = 0
        self._flat: tuple[FloatArray, ...] = ()
        self._views: dict[int, tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]] = {}

    def __call__(self, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(rows (n_points + len(which), m), x - px0, y - py0, their squared length): views valid until the next
        call."""
        k, m = self.norms, len(x)
        DX, DY, square, rows, t = self._scratch(m)
        np.subtract(x, self.px, out=DX)
        np.subtract(y, self.py, out=DY)
        np.multiply(DX[:k], DX[:k], out=square)
        np.multiply(DY[:k], DY[:k], out=rows[:k])      # rows[:k] as a temporary: DY^2
        square += rows[:k]
        np.sqrt(square, out=rows[:k])
        rows[self.first_circle:k] -= self.circle_r
        if k < len(rows):
            ax, ay, temp = DX[k:], DY[k:], rows[k:]    # rows[k:] as a temporary until the walls' distances
            np.multiply(ax, self.seg_dx, out=t)
            np.multiply(ay, self.seg_dy, out=temp)
            t += temp
            t *= self.seg_inv_length2
            np.maximum(t, 0.0, out=t)
            np.minimum(t, 1.0, out=t)
            np.multiply(t, self.seg_dx, out=temp)
            ax -= temp
            t *= self.seg_dy
            ay -= t
            ax *= ax
            ay *= ay
            ax += ay
            np.sqrt(ax, out=temp)
        return rows, DX[0], DY[0], square[0]

    def _scratch(self, m: int) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """DX, DY (n, m), the squares (norms, m), the rows (n, m) and the walls' temporary (n - norms, m)."""
        views = self._views.get(m)
        if views is None:
            n, k = len(self.px), self.norms
            if m > self._capacity or not self._flat:
                self._capacity = m
                self._flat = tuple(np.empty(rows * m) for rows in (n, n, k, n, n - k))
                self._views.clear()
            DX, DY, square, rows, t = (flat[:rows * m].reshape(rows, m)
                                       for flat, rows in zip(self._flat, (n, n, k, n, n - k)))
            views = self._views[m] = DX, DY, square, rows, t
        return views


def sparse_row_sum(columns: dict[int, FloatArray], n: int) -> FloatArray | None:
    """A.sum(axis=1), bit for bit, of an (m, n) array A that is +0.0 outside `columns` (index -> column of
    values >= +0.0), without building A; None when there are no columns (the sum is all +0.0).

    numpy sums each row of a C-ordered array pairwise: fewer than 8 values one after another from 0.0; up to
    128 values in eight interleaved partial sums (value i goes to partial i % 8) combined as a tree, then
    the last n % 8 values one after another; more values in two halves. Adding +0.0 changes no value, so
    adding the given columns alone, each where the tree puts it, gives the same floats. (numpy is pinned in
    requirements.txt; tests/fastep_core/planning/swarm/test_step_terms.py checks this against numpy itself.)
    """
    def add(u: FloatArray | None, v: FloatArray | None) -> FloatArray | None:
        return v if u is None else u if v is None else u + v

    def total(start: int, count: int) -> FloatArray | None:
        if not any(start <= k < start + count for k in columns):
            return None
        if count < 8:
            result = None
            for k in range(start, start + count):
                result = add(result, columns.get(k))
            return result
        if count <= 128:
            body = count - count % 8
            part = [columns.get(start + j) for j in range(8)]
            for i in range(8, body, 8):
                for j in range(8):
                    part[j] = add(part[j], columns.get(start + i + j))
            result = add(add(add(part[0], part[1]), add(part[2], part[3])),
                         add(add(part[4], part[5]), add(part[6], part[7])))
            for k in range(start + body, start + count):
                result = add(result, columns.get(k))
            return result
        half = count // 2
        half -= half % 8
        return add(total(start, half), total(start + half, count - half))

    return total(0, n)


def near_row_sum(near: NDArray[np.intp], rows: FloatArray, n: int) -> FloatArray | None:
    """A.sum(axis=1) of the (m, n) array A that holds rows[i] in column near[i] and +0.0 elsewhere; None when no
    column is set. From DENSE_FROM columns on and for fewer than DENSE_BELOW rows, A is built and numpy sums it (its
    own floats, by definition); otherwise sparse_row_sum adds the columns alone to the same bits. A small A costs
    less than adding 4-15 columns one by one in Python; a large one more."""
    if not len(near):
        return None
    if len(near) >= DENSE_FROM and rows.shape[1] < DENSE_BELOW:
        full = np.zeros((rows.shape[1], n))
        full[:, near] = rows.T
        total: FloatArray = full.sum(axis=1)
        return total
    return sparse_row_sum({int(k): row for k, row in zip(near, rows)}, n)
