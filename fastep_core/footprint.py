"""A robot's real outline: a polygon in its own frame (base_link), as Nav2's costmap parameter `footprint` gives it.

A robot with a footprint is planned as Nav2 plans one (fastep_core/planning/outline.py): its route and swarm with
the inscribed circle plus a margin, the guard and backing up with the polygon placed along the predicted motion,
other robots kept from its circumscribed circle (`Footprint.radius`); it is judged against the world with the
polygon itself, placed at each pose (`Footprint.clearance`).

The rules (`Footprint.parse`, and every Footprint made): at least 3 vertices, finite, a non-zero area, no edge
touching another but its neighbours, and base_link strictly inside. Nav2 does not ask the last, fastep does: its
planners place the robot by base_link and turn it about base_link, and a base_link outside the outline is far more
often a footprint written in another frame than a real robot. Clockwise vertices (Nav2 takes either order;
its own documentation's example is clockwise) are reordered counter-clockwise.

Clearance is signed: the distance between the placed polygon and an obstacle when they are apart; when they
overlap, minus the depth of the obstacle's deepest point inside the polygon (its distance to the outline), so a
cylinder wholly inside the box counts. For a circle that is exact for any polygon; for a wall it is exact for a
convex polygon and a lower bound on the depth otherwise (the sign is exact for both).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fastep_core.geometry import Obstacles, norm, segment_segment_distance

__all__ = ['MAX_EXTENT', 'MAX_VERTICES', 'Footprint']

FloatArray = NDArray[np.float64]
MAX_VERTICES = 1000           # a footprint is a robot's outline, not a map
MAX_EXTENT = 1000.0           # m from base_link along x or y (msg_tools.footprint.MAX_FOOTPRINT_RADIUS)
_MAX_TEXT = 100_000           # characters of Nav2's string form
_CHUNK = 1_000_000            # (pose, obstacle, edge) elements per step of clearance: bounds its memory
_NUMBER = re.compile(r'[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan)', re.IGNORECASE)
_TOKEN = re.compile(r'\s*(?:(\[)|(\])|(,)|([^\s\[\],]+))')


def _text_pairs(text: str, what: str) -> list[list[float]]:
    """Nav2's string form "[[x, y], [x, y], ...]" read token by token (brackets, commas, numbers): no eval, no
    YAML, nesting at most two deep, as nav2_costmap_2d's parseVVF reads it."""
    if len(text) > _MAX_TEXT:
        raise ValueError(f'{what} is {len(text)} characters long, more than {_MAX_TEXT}')
    tokens: list[str] = []
    position = 0
    stripped = text.rstrip()
    while position < len(stripped):
        match = _TOKEN.match(stripped, position)
        if match is None:   # only trailing blanks, which rstrip removed
            break
        tokens.append(match.group(match.lastindex or 0))
        position = match.end()
    form = 'must be a list of [x, y] pairs like "[[0.25, 0.2], [-0.25, 0.2], [-0.25, -0.2], [0.25, -0.2]]"'
    if len(tokens) < 2 or tokens[0] != '[' or tokens[-1] != ']':
        raise ValueError(f'{what} {form}, got {text.strip()[:60]!r}')
    pairs: list[list[float]] = []
    k = 1
    while k < len(tokens) - 1:
        # one pair: '[' number ',' number ']', then ',' unless it is the last
        pair = tokens[k:k + 5]
        if len(pair) < 5 or pair[0] != '[' or pair[2] != ',' or pair[4] != ']':
            raise ValueError(f'{what} {form}, got {text.strip()[:60]!r}')
        values = []
        for token in (pair[1], pair[3]):
            if not _NUMBER.fullmatch(token):
                raise ValueError(f'{what}[{len(pairs)}]: {token[:30]!r} is not a number')
            values.append(float(token))
        pairs.append(values)
        k += 5
        if k < len(tokens) - 1:
            if tokens[k] != ',':
                raise ValueError(f'{what} {form}, got {text.strip()[:60]!r}')
            k += 1
    return pairs


def _pairs(value: Any, what: str) -> FloatArray:
    """Vertices (N, 2) from Nav2's string form, a list of [x, y] pairs or an (N, 2) array."""
    if isinstance(value, str):
        value = _text_pairs(value, what)
    if isinstance(value, np.ndarray):
        if value.ndim != 2 or value.shape[1] != 2 or value.dtype.kind not in 'iuf':
            raise ValueError(f'{what} must be an (N, 2) array of numbers, got shape {value.shape} ({value.dtype})')
        return np.array(value, dtype=float)
    if not isinstance(value, (list, tuple)):
        raise ValueError(f'{what} must be a list of [x, y] pairs, got {type(value).__name__}')
    if len(value) > MAX_VERTICES:
        raise ValueError(f'{what} has {len(value)} vertices, more than {MAX_VERTICES}')
    rows = []
    for i, pair in enumerate(value):
        if not isinstance(pair, (list, tuple, np.ndarray)) or len(pair) != 2:
            raise ValueError(f'{what}[{i}] must be a pair [x, y], got {str(pair)[:40]}')
        for v in pair:
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
                raise ValueError(f'{what}[{i}] must be two numbers [x, y], got {str(list(pair))[:40]}')
        try:
            rows.append((float(pair[0]), float(pair[1])))
        except OverflowError:   # an integer beyond any float
            raise ValueError(f'{what}[{i}] is beyond any float, got {str(list(pair))[:40]}') from None
    return np.array(rows, dtype=float).reshape(-1, 2)


def _signed_area(v: FloatArray) -> float:
    x, y = v[:, 0], v[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _checked(value: Any, what: str) -> FloatArray:
    """The vertices counter-clockwise, or ValueError (one line) naming what is wrong."""
    v = _pairs(value, what)
    n = len(v)
    if n < 3:
        raise ValueError(f'{what} needs at least 3 vertices, got {n}')
    if n > MAX_VERTICES:
        raise ValueError(f'{what} has {n} vertices, more than {MAX_VERTICES}')
    bad = np.nonzero(~np.isfinite(v).all(axis=1))[0]
    if len(bad):
        raise ValueError(f'{what}[{bad[0]}] must be finite, got {v[bad[0]].tolist()}')
    scale = float(np.abs(v).max())
    if scale > MAX_EXTENT:
        raise ValueError(f'{what}[{int(np.abs(v).max(axis=1).argmax())}] lies {scale:g} m from base_link, more '
                         f'than {MAX_EXTENT:g} m: not a robot')
    tiny = 1e-12 * scale
    edge = np.roll(v, -1, axis=0) - v
    length = norm(edge[:, 0], edge[:, 1])
    if (length <= tiny).any():
        k = int(np.argmax(length <= tiny))
        raise ValueError(f'{what} repeats a vertex: {v[k].tolist()} twice in a row')
    # Edges that are not neighbours may not touch at all (a bow-tie's cross, a loop).
    a, b = v, np.roll(v, -1, axis=0)
    i, j = np.triu_indices(n, 2)
    apart = ~((i == 0) & (j == n - 1))
    i, j = i[apart], j[apart]
    touching = segment_segment_distance(a[i], b[i], a[j], b[j]) <= 1e-9 * scale
    if touching.any():
        raise ValueError(f'{what} intersects itself (edges {int(i[touching][0])} and {int(j[touching][0])} touch)')
    area = _signed_area(v)
    if abs(area) <= 1e-12 * max(scale * scale, 1e-300):
        raise ValueError(f'{what} has zero area (its vertices lie on one line)')
    # Neighbouring edges that fold back onto each other (a spike of zero width) overlap along a stretch.
    nxt = np.roll(edge, -1, axis=0)
    cross = edge[:, 0] * nxt[:, 1] - edge[:, 1] * nxt[:, 0]
    folds = (np.abs(cross) <= 1e-12 * length * np.roll(length, -1)) & (np.einsum('ij,ij->i', edge, nxt) < 0.0)
    if folds.any():
        k = int(np.argmax(folds))
        raise ValueError(f'{what} intersects itself (edges {k} and {(k + 1) % n} fold back onto each other)')
    if area < 0.0:          # clockwise: the same outline counter-clockwise
        v = v[::-1].copy()
    if not _inside(v, np.zeros((1, 2)))[0] or float(_boundary_distance(v, np.zeros((1, 2)))[0]) <= tiny:
        raise ValueError(f'{what} must hold base_link (0, 0) inside it: fastep places and turns the robot by '
                         f'base_link (is the footprint in another frame?)')
    return v


def _boundary_distance(v: FloatArray, q: FloatArray) -> FloatArray:
    """Distance from points q (..., 2) to the outline of polygon v (N, 2): shape (...)."""
    a = v
    ab = np.roll(v, -1, axis=0) - a
    inv = 1.0 / np.einsum('ij,ij->i', ab, ab)
    qx, qy = q[..., 0, None] - a[:, 0], q[..., 1, None] - a[:, 1]
    t = np.minimum(np.maximum((qx * ab[:, 0] + qy * ab[:, 1]) * inv, 0.0), 1.0)
    out: FloatArray = norm(qx - t * ab[:, 0], qy - t * ab[:, 1]).min(axis=-1)
    return out


def _inside(v: FloatArray, q: FloatArray) -> NDArray[np.bool_]:
    """Whether points q (..., 2) lie inside polygon v (N, 2) (the even-odd rule, a ray toward +x)."""
    ax, ay = v[:, 0], v[:, 1]
    bx, by = np.roll(ax, -1), np.roll(ay, -1)
    qx, qy = q[..., 0, None], q[..., 1, None]
    straddles = (ay > qy) != (by > qy)
    with np.errstate(divide='ignore', invalid='ignore'):
        crossing_x = ax + (qy - ay) * (bx - ax) / (by - ay)
    inside: NDArray[np.bool_] = (np.count_nonzero(straddles & (qx < crossing_x), axis=-1) % 2) == 1
    return inside


@dataclass(frozen=True, eq=False)
class Footprint:
    """A robot's outline: vertices (N, 2) in the robot frame (base_link), counter-clockwise, read-only."""

    vertices: FloatArray
    _normals: FloatArray = field(init=False, repr=False)     # each edge's inward unit normal (N, 2)

    def __post_init__(self) -> None:
        v = _checked(self.vertices, 'footprint')
        v.setflags(write=False)
        object.__setattr__(self, 'vertices', v)
        edge = np.roll(v, -1, axis=0) - v
        normals = np.column_stack([-edge[:, 1], edge[:, 0]]) / norm(edge[:, 0], edge[:, 1])[:, None]
        normals.setflags(write=False)
        object.__setattr__(self, '_normals', normals)

    @classmethod
    def parse(cls, value: Any, what: str = 'footprint') -> Footprint:
        """A footprint from Nav2's string form "[[x, y], [x, y], ...]", a list of [x, y] pairs or an (N, 2)
        array; ValueError with one line starting with `what` for anything that is not a valid outline."""
        return cls(_checked(value, what))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Footprint):
            return NotImplemented
        return bool(np.array_equal(self.vertices, other.vertices))

    def __hash__(self) -> int:
        return hash(self.vertices.tobytes())

    def __repr__(self) -> str:
        return f'Footprint({self.vertices.tolist()})'

    def to_list(self) -> list[list[float]]:
        """The vertices as [[x, y], ...] (what a scenario file or Nav2's parameter holds)."""
        return [[float(x), float(y)] for x, y in self.vertices]

    @property
    def radius(self) -> float:
        """The circumscribed radius about base_link: the farthest vertex (the conservative circle)."""
        return float(norm(self.vertices[:, 0], self.vertices[:, 1]).max())

    @property
    def inscribed(self) -> float:
        """The distance from base_link to the nearest edge (the largest circle about base_link inside)."""
        return float(_boundary_distance(self.vertices, np.zeros(2)))

    def placed(self, x: ArrayLike, y: ArrayLike, yaw: ArrayLike) -> FloatArray:
        """The world vertices at poses (x, y, yaw), broadcasting: shape (..., N, 2)."""
        px, py, th = (np.asarray(a, dtype=float)[..., None] for a in (x, y, yaw))
        c, s = np.cos(th), np.sin(th)
        vx, vy = self.vertices[:, 0], self.vertices[:, 1]
        return np.stack([px + c * vx - s * vy, py + s * vx + c * vy], axis=-1)

    # ------------------------------------------------------------------------------------------- clearance

    def _to_body(self, poses: FloatArray, points: FloatArray) -> FloatArray:
        """World points (M, 2), or (..., M, 2) matching the poses, in the robot frame at poses (..., 3):
        shape (..., M, 2)."""
        c, s = np.cos(poses[..., 2, None]), np.sin(poses[..., 2, None])
        dx, dy = points[..., 0] - poses[..., 0, None], points[..., 1] - poses[..., 1, None]
        return np.stack([c * dx + s * dy, c * dy - s * dx], axis=-1)

    def _signed(self, q: FloatArray) -> FloatArray:
        """Signed distance of body-frame points q (..., 2) to the polygon: negative inside."""
        d = _boundary_distance(self.vertices, q)
        return np.where(_inside(self.vertices, q), -d, d)

    def circle_distances(self, poses: ArrayLike, centres: ArrayLike, radii: ArrayLike) -> FloatArray:
        """Signed clearance of the footprint at poses (..., 3) to circles: centres (M, 2), or (..., M, 2) per pose
        (movers), radii (M,): shape (..., M)."""
        p = np.asarray(poses, dtype=float)
        q = self._to_body(p, np.asarray(centres, dtype=float))
        out: FloatArray = self._signed(q) - np.asarray(radii, dtype=float)
        return out

    def segment_distances(self, poses: ArrayLike, starts: ArrayLike, ends: ArrayLike) -> FloatArray:
        """Signed clearance of the footprint at poses (..., 3) to walls starts-ends (W, 2): shape (..., W)."""
        p = np.asarray(poses, dtype=float)
        a = self._to_body(p, np.asarray(starts, dtype=float))          # (..., W, 2)
        b = self._to_body(p, np.asarray(ends, dtype=float))
        v = self.vertices
        w = np.roll(v, -1, axis=0)
        apart = segment_segment_distance(a[..., None, :], b[..., None, :], v, w).min(axis=-1)   # (..., W)
        # Depth along a wall a + t (b - a): to edge k's line it is c_k + t s_k; inside a convex polygon the
        # depth is the least of them, a concave function of t whose maximum lies at an end of the wall or where
        # two of them are equal. Those points' true depth (to the outline) is the wall's depth.
        n = self._normals
        c = (a[..., None, 0] - v[:, 0]) * n[:, 0] + (a[..., None, 1] - v[:, 1]) * n[:, 1]     # (..., W, N)
        s = (b[..., None, 0] - a[..., None, 0]) * n[:, 0] + (b[..., None, 1] - a[..., None, 1]) * n[:, 1]
        i, j = np.triu_indices(len(v), 1)
        with np.errstate(divide='ignore', invalid='ignore'):
            t = (c[..., j] - c[..., i]) / (s[..., i] - s[..., j])
        t = np.where(np.isfinite(t), np.clip(t, 0.0, 1.0), 0.0)
        t = np.concatenate([np.zeros(t.shape[:-1] + (1,)), np.ones(t.shape[:-1] + (1,)), t], axis=-1)
        points = a[..., None, :] + t[..., None] * (b - a)[..., None, :]                          # (..., W, K, 2)
        depth = np.maximum(-self._signed(points), 0.0).max(axis=-1)
        overlap = (apart <= 0.0) | _inside(v, a)
        out: FloatArray = np.where(overlap, -depth, apart)
        return out

    def distances(self, poses: ArrayLike, obstacles: Obstacles) -> FloatArray:
        """Signed clearance of the footprint at poses (..., 3) to each obstacle: shape (..., n_obstacles), circles
        first (as Obstacles.distances)."""
        p = np.asarray(poses, dtype=float)
        parts = [self.circle_distances(p, obstacles.centers, obstacles.radii)]
        if len(obstacles.starts):
            parts.append(self.segment_distances(p, obstacles.starts, obstacles.ends))
        return np.concatenate(parts, axis=-1)

    def clearance(self, poses: ArrayLike, obstacles: Obstacles) -> FloatArray:
        """Signed clearance of the footprint at poses (..., 3) to the nearest obstacle: shape (...), negative
        where it overlaps one, inf with no obstacles. Poses are taken in chunks that bound the memory."""
        p = np.asarray(poses, dtype=float)
        flat = p.reshape(-1, 3)
        if not len(obstacles):
            return np.full(p.shape[:-1], np.inf)
        n = len(self.vertices)
        per_pose = max(1, obstacles.n_circles * n + len(obstacles.starts) * n * n)
        size = max(1, _CHUNK // per_pose)
        out = np.concatenate([self.distances(flat[k:k + size], obstacles).min(axis=-1)
                              for k in range(0, len(flat), size)]) if len(flat) else np.zeros(0)
        return out.reshape(p.shape[:-1])

    def holds(self, other_radius: float) -> bool:
        """Whether a circle of `other_radius` about base_link covers the footprint (with rounding slack)."""
        return other_radius >= self.radius * (1.0 - 1e-9)

