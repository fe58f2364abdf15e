"""The exact reference: the shortest path that keeps a clearance r from every obstacle and the border.

Why: FAStep-Kinematic and ACO-Kinematic are judged by path length, and the paper compares them only with
each other and with the straight line. A straight line is a poor yardstick once something is in the way; the
true optimum (for a point that must stay r away from every obstacle surface) says how much shorter any
planner could possibly be. With circles and line segments only, it has a closed form.

The method (a tangent visibility graph, exact for discs; Chen & Wang's "shortest paths among disks"):
- Inflate every obstacle by r. A circle of radius rho becomes a disc of radius rho + r. A segment becomes a
  capsule: its two end-cap discs of radius r plus the strip of half-width r between them. A shortest path
  bends only where it wraps around an obstacle's convex boundary; the straight sides of a capsule are the
  common tangents of its two end caps, so the caps alone (as circles) generate every bend, and the capsule
  enters only as a constraint: no straight edge and no arc may come closer than r to the segment.
- Nodes are start, goal and the tangent points of every common tangent between two circles (four per pair:
  two outer, two inner when they are apart) and between start or goal and a circle (two each). A tangent
  edge is kept when the core's own `Obstacles.path_clearance` of it is at least r (minus TOL) and both of its
  ends lie in the workspace shrunk by the border margin (convex, so the whole edge then does).
- Arc edges join consecutive nodes along each circle (either way round, as long as the arc is free). The
  free part of a circle is computed in closed form: the angles where it enters another inflated disc, the
  strip of a capsule, or leaves the shrunk workspace are intervals of the form {A cos t + B sin t < h}.
- Dijkstra (heapq) from start to goal; the path's length is exact (tangent lengths plus R * angle).

The border: planned waypoints keep `clearance` from it too (as the step planner's rule does), except that a
start or goal that is nearer the border lowers that margin to its own distance, so it is never excluded.
A start or goal closer than `clearance` to an obstacle has no valid path (None).

The polyline: arcs are replaced by a circumscribed polygon (vertices R / cos(delta / 2) from the centre,
spaced at most `spacing` along the arc), whose every chord stays outside the inflated circle, so the polyline
keeps clearance r everywhere, not only at its vertices; each chord is checked with `path_clearance` and
refined where a neighbouring obstacle is tighter than the polygon's bulge. Its length exceeds the exact length
by a factor of about 1 + delta^2 / 12 on arcs (0.06 % at 0.25 m spacing on a 3 m circle).
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.errors import ParameterError
from fastep_core.geometry import Circle, Segment
from fastep_core.world import World

__all__ = ['OptimalPath', 'PathPiece', 'shortest_path', 'TOL', 'main']

FloatArray = NDArray[np.float64]
ArcShape = tuple[int, float, float]   # an arc edge: (circle index, angle at its start, signed sweep)
TOL = 1e-9
"""Absolute slack (m) on every clearance test, so tangential contact counts as free."""
TWO_PI = 2.0 * math.pi
_MAX_REFINE = 12          # a chord is split at most 2^12 times when a neighbour is tighter than the bulge


@dataclass(frozen=True)
class PathPiece:
    """One piece of the exact path: a straight tangent ('line') or an arc along an inflated circle ('arc')."""

    kind: str                               # 'line' | 'arc'
    start: tuple[float, float]
    end: tuple[float, float]
    length: float
    center: tuple[float, float] | None = None   # arcs only
    radius: float = 0.0                          # arcs only
    angle0: float = 0.0                          # arcs only: start angle (rad)
    sweep: float = 0.0                           # arcs only: signed angle swept (rad, + = counter-clockwise)

    def sample(self, step: float) -> FloatArray:
        """Points on the exact piece, at most `step` apart, both ends included: (k, 2)."""
        k = max(1, int(math.ceil(self.length / step)))
        s = np.linspace(0.0, 1.0, k + 1)
        if self.kind == 'line':
            a, b = np.array(self.start), np.array(self.end)
            line: FloatArray = a + s[:, None] * (b - a)
            return line
        assert self.center is not None
        t = self.angle0 + s * self.sweep
        return np.column_stack([self.center[0] + self.radius * np.cos(t), self.center[1] + self.radius * np.sin(t)])


@dataclass(frozen=True)
class OptimalPath:
    """The shortest path keeping `clearance`: exact length, its pieces, and a polyline that keeps it too.

    length: exact length (m). points: polyline (n, 2) from start to goal; arcs as circumscribed polygons.
    pieces: the exact lines and arcs. clearance: the r it keeps. border: the margin kept from the workspace
    border. nodes, edges: size of the visibility graph.
    """

    length: float
    points: FloatArray
    pieces: tuple[PathPiece, ...]
    clearance: float
    border: float
    nodes: int
    edges: int

    @property
    def polyline_length(self) -> float:
        return float(np.hypot(*np.diff(self.points, axis=0).T).sum()) if len(self.points) > 1 else 0.0

    def sample(self, step: float = 0.01) -> FloatArray:
        """Dense points on the exact path (for checks and figures)."""
        if not self.pieces:
            return self.points.copy()
        return np.concatenate([p.sample(step) for p in self.pieces])


# ----------------------------------------------------------------------------------------- angular sets

Pieces = list[tuple[float, float]]     # disjoint-or-not open intervals inside [0, 2 pi]


def _wrap(t: float) -> float:
    t = math.fmod(t, TWO_PI)
    return t + TWO_PI if t < 0.0 else t


def _arc_pieces(lo: float, width: float) -> Pieces:
    """The circular interval (lo, lo + width) as at most two intervals inside [0, 2 pi]."""
    if width >= TWO_PI:
        return [(0.0, TWO_PI)]
    if width <= 0.0:
        return []
    lo = _wrap(lo)
    hi = lo + width
    if hi <= TWO_PI:
        return [(lo, hi)]
    return [(lo, TWO_PI), (0.0, hi - TWO_PI)]


def _below(A: float, B: float, h: float) -> Pieces:
    """{t : A cos t + B sin t < h} as intervals inside [0, 2 pi]."""
    rho = math.hypot(A, B)
    if rho <= 1e-300:
        return [(0.0, TWO_PI)] if h > 0.0 else []
    if h >= rho:
        return [(0.0, TWO_PI)]
    if h <= -rho:
        return []
    alpha = math.acos(h / rho)
    return _arc_pieces(math.atan2(B, A) + alpha, TWO_PI - 2.0 * alpha)


def _intersect(a: Pieces, b: Pieces) -> Pieces:
    out = []
    for lo1, hi1 in a:
        for lo2, hi2 in b:
            lo, hi = max(lo1, lo2), min(hi1, hi2)
            if hi > lo:
                out.append((lo, hi))
    return out


def _overlaps(arc: Pieces, blocked: Pieces) -> bool:
    return any(min(h1, h2) - max(l1, l2) > 1e-12 for l1, h1 in arc for l2, h2 in blocked)


# ----------------------------------------------------------------------------------------- the graph

@dataclass(frozen=True)
class _Circle:
    center: tuple[float, float]
    radius: float           # inflated radius


class _Problem:
    """Inflated circles, their blocked arcs and the edge test for one (world, clearance, border)."""

    def __init__(self, world: World, clearance: float, border: float) -> None:
        self.world = world
        self.clearance = clearance
        self.border = border
        xmin, ymin, xmax, ymax = world.workspace
        self.box = (xmin + border - TOL, ymin + border - TOL, xmax - border + TOL, ymax - border + TOL)
        circles = [o for o in world.obstacle_list if isinstance(o, Circle)]
        segments = [o for o in world.obstacle_list if isinstance(o, Segment)]
        self.disc_obstacles = [_Circle(c.center, c.radius + clearance) for c in circles]
        self.segments = segments
        self.circles: list[_Circle] = list(self.disc_obstacles)
        for s in segments:
            self.circles.append(_Circle(s.start, clearance))
            self.circles.append(_Circle(s.end, clearance))
        self.blocked = [self._blocked(k) for k in range(len(self.circles))]

    # ------------------------------------------------------------------ free arcs of one circle
    def _blocked(self, k: int) -> Pieces:
        """Angles of circle k whose points are closer than clearance (minus TOL) to something, or outside."""
        c = self.circles[k]
        cx, cy = c.center
        R = c.radius
        out: Pieces = []
        for j, d in enumerate(self.disc_obstacles):
            if j == k:
                continue
            wx, wy = cx - d.center[0], cy - d.center[1]
            q = d.radius - TOL
            out += _below(wx, wy, (q * q - R * R - wx * wx - wy * wy) / (2.0 * R))
        r = self.clearance - TOL
        for s in self.segments:
            for end in (s.start, s.end):      # the end-cap discs
                wx, wy = cx - end[0], cy - end[1]
                out += _below(wx, wy, (r * r - R * R - wx * wx - wy * wy) / (2.0 * R))
            ax, ay = s.start
            ux, uy = s.end[0] - ax, s.end[1] - ay
            L = math.hypot(ux, uy)
            ux, uy = ux / L, uy / L
            nx, ny = -uy, ux
            pn = nx * (cx - ax) + ny * (cy - ay)      # p = c + R e(t): n.(p - a) = pn + R n.e
            pu = ux * (cx - ax) + uy * (cy - ay)
            strip = _below(R * nx, R * ny, r - pn)                          # n.(p - a) < r
            strip = _intersect(strip, _below(-R * nx, -R * ny, r + pn))     # n.(p - a) > -r
            strip = _intersect(strip, _below(-R * ux, -R * uy, pu))         # u.(p - a) > 0
            strip = _intersect(strip, _below(R * ux, R * uy, L - pu))       # u.(p - a) < L
            out += strip
        bx0, by0, bx1, by1 = self.box
        out += _below(R, 0.0, bx0 - cx)         # x < xmin + border
        out += _below(-R, 0.0, cx - bx1)        # x > xmax - border
        out += _below(0.0, R, by0 - cy)
        out += _below(0.0, -R, cy - by1)
        return out

    def arc_free(self, k: int, angle0: float, sweep: float) -> bool:
        if sweep < 0.0:
            angle0, sweep = angle0 + sweep, -sweep
        return not _overlaps(_arc_pieces(angle0, sweep), self.blocked[k])

    # ------------------------------------------------------------------ straight edges
    def inside(self, P: FloatArray) -> NDArray[np.bool_]:
        bx0, by0, bx1, by1 = self.box
        return (P[:, 0] >= bx0) & (P[:, 0] <= bx1) & (P[:, 1] >= by0) & (P[:, 1] <= by1)

    def edges_free(self, P: FloatArray, Q: FloatArray) -> NDArray[np.bool_]:
        """Which straight edges P[i]-Q[i] keep the clearance and stay in the shrunk workspace."""
        ok = self.inside(P) & self.inside(Q)
        obstacles = self.world.obstacles
        if len(obstacles) and ok.any():
            idx = np.flatnonzero(ok)
            ok[idx] = obstacles.path_clearance(P[idx], Q[idx]) >= self.clearance - TOL
        return ok


def _tangents(c1: tuple[float, float], r1: float, c2: tuple[float, float], r2: float,
              inner: bool) -> list[tuple[np.ndarray, np.ndarray]]:
    """Common tangents of two circles (r2 = 0: tangents from a point), as (point on 1, point on 2) pairs.

    Outer tangents (inner=False) touch both circles on the same side, inner ones cross between them.
    """
    dx, dy = c2[0] - c1[0], c2[1] - c1[1]
    D = math.hypot(dx, dy)
    if D <= 1e-12:
        return []
    s2 = -r2 if inner else r2
    ratio = (r1 - s2) / D
    if abs(ratio) > 1.0:
        return []
    vx, vy = dx / D, dy / D
    h = math.sqrt(max(0.0, 1.0 - ratio * ratio))
    out = []
    for k in ((1.0, -1.0) if h > 0.0 else (1.0,)):
        nx, ny = vx * ratio - k * h * vy, vy * ratio + k * h * vx
        p1 = np.array([c1[0] + r1 * nx, c1[1] + r1 * ny])
        p2 = np.array([c2[0] + s2 * nx, c2[1] + s2 * ny])
        out.append((p1, p2))
    return out


class _Graph:
    """Nodes (points, with the circle they lie on or -1) and weighted undirected edges with their shape."""

    def __init__(self) -> None:
        self.points: list[np.ndarray] = []
        self.circle: list[int] = []
        self.adj: dict[int, dict[int, tuple[float, ArcShape | None]]] = {}

    def node(self, point: np.ndarray, circle: int) -> int:
        self.points.append(point)
        self.circle.append(circle)
        return len(self.points) - 1

    def edge(self, u: int, v: int, length: float, shape: ArcShape | None) -> None:
        """shape: None for a line, (circle, angle at u, signed sweep u -> v) for an arc."""
        old = self.adj.setdefault(u, {}).get(v)
        if old is None or length < old[0]:
            self.adj[u][v] = (length, shape)
            if shape is None:
                back = None
            else:
                k, a0, sweep = shape
                back = (k, a0 + sweep, -sweep)
            self.adj.setdefault(v, {})[u] = (length, back)

    @property
    def n_edges(self) -> int:
        return sum(len(v) for v in self.adj.values()) // 2

    def dijkstra(self, source: int, target: int) -> list[int] | None:
        dist = {source: 0.0}
        prev: dict[int, int] = {}
        heap = [(0.0, source)]
        done = set()
        while heap:
            d, u = heapq.heappop(heap)
            if u in done:
                continue
            if u == target:
                break
            done.add(u)
            for v, (w, _) in self.adj.get(u, {}).items():
                nd = d + w
                if nd < dist.get(v, math.inf):
                    dist[v], prev[v] = nd, u
                    heapq.heappush(heap, (nd, v))
        if target not in dist:
            return None
        path = [target]
        while path[-1] != source:
            path.append(prev[path[-1]])
        return path[::-1]


def _build(problem: _Problem, start: np.ndarray, goal: np.ndarray) -> _Graph:
    graph = _Graph()
    s, g = graph.node(start, -1), graph.node(goal, -1)
    circles = problem.circles
    cand_u: list[tuple[np.ndarray, int, int]] = []      # (point, circle, existing node or -1)
    cand_v: list[tuple[np.ndarray, int, int]] = []
    cand_u.append((start, -1, s))
    cand_v.append((goal, -1, g))
    for node, point in ((s, start), (g, goal)):
        for k, c in enumerate(circles):
            for p_circle, _ in _tangents(c.center, c.radius, (point[0], point[1]), 0.0, inner=False):
                cand_u.append((point, -1, node))
                cand_v.append((p_circle, k, -1))
    for i in range(len(circles)):
        for j in range(i + 1, len(circles)):
            a, b = circles[i], circles[j]
            for inner in (False, True):
                for p1, p2 in _tangents(a.center, a.radius, b.center, b.radius, inner):
                    cand_u.append((p1, i, -1))
                    cand_v.append((p2, j, -1))
    P = np.array([c[0] for c in cand_u], dtype=float).reshape(-1, 2)
    Q = np.array([c[0] for c in cand_v], dtype=float).reshape(-1, 2)
    free = problem.edges_free(P, Q)
    on_circle: dict[int, list[int]] = {}
    for (p, ki, ni), (q, kj, nj), ok in zip(cand_u, cand_v, free):
        if not ok:
            continue
        u = ni if ni >= 0 else graph.node(p, ki)
        v = nj if nj >= 0 else graph.node(q, kj)
        for node, k in ((u, ki), (v, kj)):
            if k >= 0:                          # a new tangent point (start and goal lie on no circle)
                on_circle.setdefault(k, []).append(node)
        graph.edge(u, v, float(np.hypot(*(q - p))), None)
    for k, nodes in on_circle.items():
        c = circles[k]
        angles = [(_wrap(math.atan2(graph.points[n][1] - c.center[1], graph.points[n][0] - c.center[0])), n)
                  for n in nodes]
        angles.sort()
        m = len(angles)
        if m < 2:
            continue
        for idx in range(m):
            (t0, u), (t1, v) = angles[idx], angles[(idx + 1) % m]
            sweep = t1 - t0 if idx + 1 < m else t1 + TWO_PI - t0    # counter-clockwise u -> v
            if problem.arc_free(k, t0, sweep):
                graph.edge(u, v, c.radius * sweep, (k, t0, sweep))
    return graph


# ----------------------------------------------------------------------------------------- polyline

def _arc_polygon(problem: _Problem, piece: PathPiece, spacing: float) -> list[np.ndarray]:
    """Vertices after the arc's start, ending at its end: a circumscribed polygon, refined where needed."""
    assert piece.center is not None
    cx, cy = piece.center
    R = piece.radius
    k = max(1, int(math.ceil(abs(piece.sweep) * R / spacing)))
    end = np.array(piece.end)
    for _ in range(_MAX_REFINE + 1):
        delta = piece.sweep / k
        if abs(delta) >= math.pi / 2:            # keep the bulge bounded
            k *= 2
            continue
        rv = R / math.cos(delta / 2.0)
        t = piece.angle0 + delta * (np.arange(k) + 0.5)
        verts = np.column_stack([cx + rv * np.cos(t), cy + rv * np.sin(t)])
        chain = np.vstack([np.array(piece.start), verts, end])
        if problem.edges_free(chain[:-1], chain[1:]).all():
            return list(verts) + [end]
        k *= 2
    return list(verts) + [end]                  # pragma: no cover - the exact arc is free, refinement converges


def _pieces(graph: _Graph, problem: _Problem, path: list[int]) -> list[PathPiece]:
    out = []
    for u, v in zip(path[:-1], path[1:]):
        length, shape = graph.adj[u][v]
        p, q = graph.points[u], graph.points[v]
        if shape is None:
            out.append(PathPiece('line', (float(p[0]), float(p[1])), (float(q[0]), float(q[1])), length))
        else:
            k, a0, sweep = shape
            if sweep == 0.0:
                continue
            c = problem.circles[k]
            out.append(PathPiece('arc', (float(p[0]), float(p[1])), (float(q[0]), float(q[1])), length,
                                 c.center, c.radius, a0, sweep))
    return out


# ----------------------------------------------------------------------------------------- the API

def shortest_path(world: World, start: Sequence[float] | FloatArray, goal: Sequence[float] | FloatArray,
                  clearance: float, *, spacing: float = 0.25) -> OptimalPath | None:
    """The shortest path from start to goal keeping `clearance` from every obstacle surface; None if none.

    `clearance` is r = robot radius + clearance margin for a planner's reference path (use the radius alone
    for the shortest collision-free path). `spacing` is the largest distance between polyline vertices on
    arcs. Returns None when no path exists, or when start or goal is closer than `clearance` to an obstacle.
    """
    if not (math.isfinite(clearance) and clearance > 0.0):
        raise ParameterError(f'clearance must be a finite number > 0, got {clearance!r}')
    if not (math.isfinite(spacing) and spacing > 0.0):
        raise ParameterError(f'spacing must be a finite number > 0, got {spacing!r}')
    a = np.array([float(start[0]), float(start[1])])
    b = np.array([float(goal[0]), float(goal[1])])
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ParameterError('start and goal must be finite')
    walls = world.wall_distance(np.array([a, b]))
    if walls.min() < 0.0:
        return None
    border = min(clearance, float(walls.min()))
    if len(world.obstacles) and float(world.obstacles.clearance(np.array([a, b])).min()) < clearance - TOL:
        return None
    problem = _Problem(world, clearance, border)
    if np.array_equal(a, b):
        return OptimalPath(0.0, np.array([a]), (), clearance, border, 1, 0)
    graph = _build(problem, a, b)
    path = graph.dijkstra(0, 1)
    if path is None:
        return None
    pieces = _pieces(graph, problem, path)
    points = [a]
    for piece in pieces:
        if piece.kind == 'line':
            points.append(np.array(piece.end))
        else:
            points.extend(_arc_polygon(problem, piece, spacing))
    return OptimalPath(float(sum(p.length for p in pieces)), np.array(points), tuple(pieces), clearance, border,
                       len(graph.points), graph.n_edges)


def main(argv: Sequence[str] | None = None) -> int:
    """Print the optimal length of every robot of the built-in scenarios (clearance radius + margin)."""
    from fastep_core.scenario import builtin_names, load_scenario
    for name in builtin_names():
        scenario = load_scenario(name)
        for spec in scenario.robots:
            r = spec.radius + scenario.planner.clearance_margin
            path = shortest_path(scenario.world, spec.start[:2], spec.goal, r)
            line = math.dist(spec.start[:2], spec.goal)
            text = 'no path' if path is None else f'{path.length:.3f} m ({path.length / line:.4f} x straight line)'
            print(f'{name} {spec.name}: r = {r:g} m, optimal {text}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
