"""The exact reference: the shortest path that keeps a clearance r from every obstacle and the border.

Why: planners are judged by path length, and a straight line is a poor yardstick once something is in the way; the
true optimum says how much shorter any planner could be. With circles and segments only it has a closed form: a
tangent visibility graph, exact for discs (Chen & Wang, "shortest paths among disks"). Obstacles are inflated by r
(a segment becomes a capsule whose end caps generate every bend, its strip only a constraint); nodes are start, goal
and the tangent points of the common tangents, kept when `Obstacles.path_clearance` is at least r (less TOL) and in
the workspace shrunk by the border margin; arcs join nodes along each circle where it is free (closed form). Edges
are tested only against nearby obstacles (ObstacleGrid) and in blocks so memory stays bounded. The search
(planning/shortest_path/tangent_search.py) builds the graph lazily with A*, then picks the path the whole graph's
Dijkstra would (fastep_testing/optimal_eager.py checks it); its length is exact. The border margin drops to a start's or
goal's own distance so it is never excluded; a start or goal within `clearance` of an obstacle has no path (None). The
polyline replaces arcs by circumscribed polygons (spacing `spacing`) so every chord keeps r, about 1 + delta^2 / 12
longer. Only the obstacles that come within r of the shrunk workspace take part (the others block no point of it: a scan
from an absurd pose leaves walls at 1e300, whose ends round to one point there); a wall of one point is its end
cap; an obstacle near the workspace with coordinates beyond MAX_COORDINATE is a ParameterError (squares overflow).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.errors import ParameterError
from fastep_core.geometry import Circle, Obstacles, Segment, point_segment_distance
from fastep_core.planning.shortest_path.obstacle_grid import ObstacleGrid
from fastep_core.planning.shortest_path.tangent_search import TWO_PI, ArcShape, search, wrap_angle
from fastep_core.world import World

__all__ = ['MAX_COORDINATE', 'OptimalPath', 'PathPiece', 'assemble', 'prepare', 'shortest_path', 'TOL', 'main']

FloatArray = NDArray[np.float64]
TOL = 1e-9
"""Absolute slack (m) on every clearance test, so tangential contact counts as free."""
_MAX_REFINE = 12          # a chord is split at most 2^12 times when a neighbour is tighter than the bulge
MAX_ARC_VERTICES = 4096   # an arc's polygon starts with at most this many vertices (a vast circle: coarser)
MAX_SAMPLES = 1_000_000   # OptimalPath.sample gives at most about this many points per piece
MAX_COORDINATE = 1e150
"""Largest |coordinate| (m) of an obstacle near the workspace (its centre, radius, a wall's ends) the exact path
works with. Its tangent and clearance tests add up to four squared coordinates (differences of them): within 1e150
that stays below the largest float (1.8e308); beyond, a square is inf, inf - inf is nan and a test that compares it
is False: a disc of radius 1e200 over the goal counted as free. Beyond it the exact path is a ParameterError (one
line), not a wrong answer; obstacles that cannot reach the workspace do not take part at all (_reaching), whatever
their coordinates. (The workspace itself is the scenario's or the map's, bounded where those are read.)"""


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
        """Points on the exact piece, at most `step` apart (at most MAX_SAMPLES + 1), both ends included: (k, 2)."""
        wanted = self.length / step
        k = max(1, min(MAX_SAMPLES, int(math.ceil(wanted)))) if math.isfinite(wanted) else MAX_SAMPLES
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
    border. nodes, edges: the part of the visibility graph the search made (nodes reached, edges made).
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


def _arc_pieces(lo: float, width: float) -> Pieces:
    """The circular interval (lo, lo + width) as at most two intervals inside [0, 2 pi]."""
    if width >= TWO_PI:
        return [(0.0, TWO_PI)]
    if width <= 0.0:
        return []
    lo = wrap_angle(lo)
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


def _covered_all_round(blocked: Pieces, depth: float = 1e-6) -> bool:
    """Is every angle of the circle at least `depth` (rad) inside a blocked interval? The depth keeps a point
    the edge test might call free (rounding at an interval's end) from counting as blocked. The ends at 0 and
    2 pi are where _arc_pieces split an interval, not ends: they are not shrunk."""
    reach = 0.0
    for lo, hi in sorted(blocked):
        lo = lo if lo <= 0.0 else lo + depth
        hi = hi if hi >= TWO_PI else hi - depth
        if lo > 0.0 and lo >= reach:
            return False
        reach = max(reach, hi)
    return reach >= TWO_PI

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
        circles, segments, self.obstacles = _reaching(world, self.box, clearance)
        """What takes part: the obstacles that come within the clearance of the box (_reaching)."""
        self.disc_obstacles = [_Circle(c.center, c.radius + clearance) for c in circles]
        self.segments = segments
        self.circles: list[_Circle] = list(self.disc_obstacles)
        caps = [_Circle(end, clearance) for s in segments for end in (s.start, s.end)]
        coordinates = [abs(v) for v in world.workspace]
        near = [abs(v) for c in self.circles + caps for v in (*c.center, c.radius)]
        self.scale = max(coordinates + near)
        """The largest coordinate (m): rounding slack grows with it."""
        if near and not max(near) <= MAX_COORDINATE:   # nan too
            raise ParameterError(f'the exact path needs obstacles within {MAX_COORDINATE:g} m of the origin; one '
                                 f'near the workspace reaches {max(near):g} m')
        self.disc_centers = np.array([d.center for d in self.disc_obstacles], dtype=float).reshape(-1, 2)
        self.disc_radii = np.array([d.radius for d in self.disc_obstacles], dtype=float)
        self.seg_starts = np.array([s.start for s in segments], dtype=float).reshape(-1, 2)
        self.seg_ends = np.array([s.end for s in segments], dtype=float).reshape(-1, 2)
        self.blocked: dict[int, Pieces] = {}
        """The blocked angles of each circle an arc was asked of."""
        self._add_caps(caps)
        self.grid = ObstacleGrid(self.obstacles, self.box, clearance - TOL, self.scale)

    def _add_caps(self, caps: list[_Circle]) -> None:
        """Add the walls' end caps that can hold a node: each corner once (walls that meet share it), and none
        blocked all round (a corner of an outline that turns toward the free side, a wall end inside another).

        Why: a map's outline has two caps at every corner, and most corners of a rasterised thin wall are
        blocked all round; the search tests every pair of circles' tangents, so the 672 caps of a furnished
        office's /map cost 27 times the pairs of its 128 that can hold a node. A cap left out as blocked has no
        free point, so no tangent to it was free; a corner's second cap only repeated the first one's tangents,
        numbered after them, which Dijkstra's tie-break never chose: the path found is the same.
        """
        seen: set[tuple[float, float]] = set()
        for cap in caps:
            if cap.center in seen:
                continue
            seen.add(cap.center)
            k = len(self.circles)
            self.circles.append(cap)
            blocked = self._blocked(k)
            if _covered_all_round(blocked):
                self.circles.pop()
            else:
                self.blocked[k] = blocked

    # ------------------------------------------------------------------ free arcs of one circle
    def _blocked(self, k: int) -> Pieces:
        """Angles of circle k whose points are closer than clearance (minus TOL) to something, or outside."""
        c = self.circles[k]
        cx, cy = c.center
        R = c.radius
        out: Pieces = []
        # Only a disc or wall that comes within R of the circle's centre (and a millimetre more) blocks any
        # of it; the others would add empty intervals (the test of each, one by one, made this O(N^2)).
        slack = 1e-3 + 1e-9 * self.scale
        near = np.hypot(cx - self.disc_centers[:, 0], cy - self.disc_centers[:, 1]) <= \
            R + self.disc_radii + slack
        for j in np.flatnonzero(near).tolist():
            d = self.disc_obstacles[j]
            if j == k:
                continue
            wx, wy = cx - d.center[0], cy - d.center[1]
            q = d.radius - TOL
            out += _below(wx, wy, (q * q - R * R - wx * wx - wy * wy) / (2.0 * R))
        r = self.clearance - TOL
        if self.segments:
            centre = np.array([cx, cy])
            reach = point_segment_distance(centre, self.seg_starts, self.seg_ends)
            near_segments = np.flatnonzero(reach <= R + r + slack).tolist()
        else:
            near_segments = []
        for s in (self.segments[i] for i in near_segments):
            for end in (s.start, s.end):      # the end-cap discs
                wx, wy = cx - end[0], cy - end[1]
                out += _below(wx, wy, (r * r - R * R - wx * wx - wy * wy) / (2.0 * R))
            ax, ay = s.start
            ux, uy = s.end[0] - ax, s.end[1] - ay
            L = math.hypot(ux, uy)
            if L == 0.0:
                continue   # a wall of one point: its capsule is its end cap, blocked above
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
        if k not in self.blocked:
            self.blocked[k] = self._blocked(k)
        return not _overlaps(_arc_pieces(angle0, sweep), self.blocked[k])

    # ------------------------------------------------------------------ straight edges
    def inside(self, P: FloatArray) -> NDArray[np.bool_]:
        bx0, by0, bx1, by1 = self.box
        return (P[:, 0] >= bx0) & (P[:, 0] <= bx1) & (P[:, 1] >= by0) & (P[:, 1] <= by1)

    def edges_free(self, P: FloatArray, Q: FloatArray) -> NDArray[np.bool_]:
        """Which straight edges P[i]-Q[i] keep the clearance and stay in the shrunk workspace.

        Exactly `Obstacles.path_clearance(P, Q) >= clearance - TOL` where inside, computed only for the
        obstacles near each edge (ObstacleGrid), in blocks of bounded size.
        """
        ok = self.inside(P) & self.inside(Q)
        if len(self.obstacles) and ok.any():
            idx = np.flatnonzero(ok)
            ok[idx] = self.grid.free(P[idx], Q[idx])
        return ok




def _reaching(world: World, box: tuple[float, float, float, float],
              clearance: float) -> tuple[list[Circle], list[Segment], Obstacles]:
    """The world's circles and walls that come within `clearance` of `box` (walls: their bounding box does; a
    rounding slack more), in their order, and their Obstacles (the world's own when that is all of them): the
    others block no point of the box, whatever their coordinates."""
    x0, y0, x1, y1 = box
    reach = clearance + 1e-3 + 1e-9 * max(abs(x0), abs(y0), abs(x1), abs(y1))
    o = world.obstacles
    c, starts, ends = o.centers, o.starts, o.ends
    with np.errstate(over='ignore', invalid='ignore'):   # far coordinates: an inf distance is beyond any reach
        outside = np.hypot(np.maximum(np.maximum(x0 - c[:, 0], c[:, 0] - x1), 0.0),
                           np.maximum(np.maximum(y0 - c[:, 1], c[:, 1] - y1), 0.0))
        near_circles = outside <= o.radii + reach
        lo, hi = np.minimum(starts, ends), np.maximum(starts, ends)
        near_walls = (lo[:, 0] <= x1 + reach) & (hi[:, 0] >= x0 - reach) & (lo[:, 1] <= y1 + reach) & \
            (hi[:, 1] >= y0 - reach)
    circles = [ob for ob in world.obstacle_list if isinstance(ob, Circle)]   # Obstacles' order: o.centers'
    walls = [ob for ob in world.obstacle_list if isinstance(ob, Segment)]
    if near_circles.all() and near_walls.all():
        return circles, walls, o
    circles = [circles[i] for i in np.flatnonzero(near_circles).tolist()]
    walls = [walls[i] for i in np.flatnonzero(near_walls).tolist()]
    return circles, walls, Obstacles([*circles, *walls])


# ----------------------------------------------------------------------------------------- polyline

def _arc_polygon(problem: _Problem, piece: PathPiece, spacing: float) -> list[np.ndarray]:
    """Vertices after the arc's start, ending at its end: a circumscribed polygon, refined where needed."""
    assert piece.center is not None
    cx, cy = piece.center
    R = piece.radius
    wanted = abs(piece.sweep) * R / spacing
    k = max(1, min(MAX_ARC_VERTICES, int(math.ceil(wanted)))) if math.isfinite(wanted) else MAX_ARC_VERTICES
    end = np.array(piece.end)
    for _ in range(_MAX_REFINE + 1):
        if k > 16 * MAX_ARC_VERTICES:            # a vast arc: coarser than `spacing`, but bounded
            break
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


def _pieces(problem: _Problem, points: Sequence[tuple[float, float]],
            steps: Sequence[tuple[float, ArcShape | None]]) -> list[PathPiece]:
    """The path's pieces: steps[i] = (length, shape) joins points[i] to points[i + 1]; empty arcs dropped."""
    out = []
    for p, q, (length, shape) in zip(points[:-1], points[1:], steps):
        if shape is None:
            out.append(PathPiece('line', p, q, length))
        else:
            k, a0, sweep = shape
            if sweep == 0.0:
                continue
            c = problem.circles[k]
            out.append(PathPiece('arc', p, q, length, c.center, c.radius, a0, sweep))
    return out


def assemble(problem: _Problem, start: FloatArray, points: Sequence[tuple[float, float]],
             steps: Sequence[tuple[float, ArcShape | None]], spacing: float, nodes: int, edges: int) -> OptimalPath:
    """The OptimalPath of a path through the graph (its nodes' points and its edges' (length, shape))."""
    pieces = _pieces(problem, points, steps)
    polyline = [start]
    for piece in pieces:
        if piece.kind == 'line':
            polyline.append(np.array(piece.end))
        else:
            polyline.extend(_arc_polygon(problem, piece, spacing))
    return OptimalPath(float(sum(p.length for p in pieces)), np.array(polyline), tuple(pieces), problem.clearance,
                       problem.border, nodes, edges)


# ----------------------------------------------------------------------------------------- the API

def shortest_path(world: World, start: Sequence[float] | FloatArray, goal: Sequence[float] | FloatArray,
                  clearance: float, *, spacing: float = 0.25) -> OptimalPath | None:
    """The shortest path from start to goal keeping `clearance` from every obstacle surface; None if none.

    `clearance` is r = robot radius + clearance margin for a planner's reference path (use the radius alone
    for the shortest collision-free path). `spacing` is the largest distance between polyline vertices on
    arcs. Returns None when no path exists, or when start or goal is closer than `clearance` to an obstacle.
    """
    prepared = prepare(world, start, goal, clearance, spacing)
    if prepared is None:
        return None
    problem, a, b = prepared
    if np.array_equal(a, b):
        return OptimalPath(0.0, np.array([a]), (), clearance, problem.border, 1, 0)
    found = search(problem, a, b)
    if found is None:
        return None
    return assemble(problem, a, found.points, found.steps, spacing, found.nodes, found.edges)


def prepare(world: World, start: Sequence[float] | FloatArray, goal: Sequence[float] | FloatArray,
            clearance: float, spacing: float) -> tuple[_Problem, FloatArray, FloatArray] | None:
    """Checked arguments: the problem, start and goal; None when start or goal is too near an obstacle or outside."""
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
    with np.errstate(over='ignore', invalid='ignore'):   # an obstacle too far for its square: inf, farther than r
        near = len(world.obstacles) and float(world.obstacles.clearance(np.array([a, b])).min()) < clearance - TOL
    if near:
        return None
    return _Problem(world, clearance, border), a, b


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
