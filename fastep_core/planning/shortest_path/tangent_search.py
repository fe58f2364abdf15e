"""The search of the exact shortest path (planning/shortest_path/optimal.py): A* over the tangent visibility graph, made
lazily.

Why: the graph has about 2 N^2 candidate tangents among N circles, and a crowd asks for hundreds of paths; a shortest
path only looks at a thin band round the straight line to the goal, which A* explores first, stopping at the goal.
Same nodes and edges as optimal.py: start, goal and both ends of every free tangent (two tangents touching a circle at
one point are two nodes joined by a zero arc); a node's edges are its tangent and the free arcs to its neighbours on
its circle, so a circle's tangents are made and tested at once (vectorised) the first time a node on it is expanded;
the start's and goal's tangents to every circle in one batch each. The heuristic (straight-line distance) is lowered
by a rounding slack so it stays admissible in floating point; nodes reopen when a shorter way turns up. Dijkstra then
runs over the expanded nodes with the whole graph's keys (distance, node number, the same numbering), so it picks the
path the whole graph's Dijkstra would, also among equally long ones. fastep_testing/optimal_eager.py keeps the eager
construction as the reference; tests/fastep_core/planning/shortest_path/test_tangent_search.py compares them on many
worlds.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Iterator, Protocol, Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ['ArcShape', 'START', 'GOAL', 'Search', 'TangentProblem', 'pair_tangents', 'search', 'wrap_angle']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
ArcShape = tuple[int, float, float]   # an arc edge: (circle index, angle at its start, signed sweep)
Edge = tuple[int, float, ArcShape | None]   # (node, length, shape: None for a line)
TWO_PI = 2.0 * math.pi
START, GOAL = 0, 1
"""The ranks of start and goal; tangent c's end e (0: on the first circle, 1: on the second) has 2 + 2 c + e."""
HEURISTIC_SLACK = 1e-9
"""The heuristic is lowered by this fraction of itself and of the world's scale: far more than rounding."""
FLOOD_EVERY = 8
"""A* steps per step of the flood from the goal (which finds a walled-in goal early)."""


class _Disc(Protocol):
    @property
    def center(self) -> tuple[float, float]: ...
    @property
    def radius(self) -> float: ...


class TangentProblem(Protocol):
    """What the search needs of optimal.py's problem: the inflated circles and the free-edge tests."""

    @property
    def circles(self) -> Sequence[_Disc]: ...
    @property
    def scale(self) -> float: ...
    def edges_free(self, P: FloatArray, Q: FloatArray) -> NDArray[np.bool_]: ...
    def arc_free(self, k: int, angle0: float, sweep: float) -> bool: ...


def wrap_angle(t: float) -> float:
    """t in [0, 2 pi)."""
    t = math.fmod(t, TWO_PI)
    return t + TWO_PI if t < 0.0 else t


def pair_tangents(c1: FloatArray, r1: FloatArray, c2: FloatArray, r2: FloatArray,
                  inner: bool) -> tuple[FloatArray, FloatArray, NDArray[np.bool_], NDArray[np.bool_]]:
    """The outer (or inner) common tangents of many pairs of circles (radius 0: a point), element by element.

    Returns the points on circle 1 and on circle 2 of the first and second tangent, shape (m, 2, 2) each
    (index 1: first, second), and which of the two exist. Every number depends on its own pair only (the
    distance with math.hypot), so a pair's tangents are the same bit for bit in whichever batch.
    """
    dx, dy = c2[:, 0] - c1[:, 0], c2[:, 1] - c1[:, 1]
    D = np.array([math.hypot(x, y) for x, y in zip(dx.tolist(), dy.tolist())], dtype=float)
    apart = D > 1e-12
    D = np.where(apart, D, 1.0)
    s2 = -r2 if inner else r2
    ratio = (r1 - s2) / D
    first = apart & ~(np.abs(ratio) > 1.0)
    vx, vy = dx / D, dy / D
    with np.errstate(invalid='ignore'):
        h = np.sqrt(np.maximum(0.0, 1.0 - ratio * ratio))
    second = first & (h > 0.0)
    on1 = np.empty((len(D), 2, 2))
    on2 = np.empty((len(D), 2, 2))
    for slot, k in enumerate((1.0, -1.0)):
        kh = k * h
        nx, ny = vx * ratio - kh * vy, vy * ratio + kh * vx
        on1[:, slot, 0], on1[:, slot, 1] = c1[:, 0] + r1 * nx, c1[:, 1] + r1 * ny
        on2[:, slot, 0], on2[:, slot, 1] = c2[:, 0] + s2 * nx, c2[:, 1] + s2 * ny
    return on1, on2, first, second


def pair_rank(i: IntArray, j: IntArray, n: int) -> IntArray:
    """The index of the pair (i, j), i < j, among all pairs of n circles taken row by row."""
    return i * (2 * n - i - 1) // 2 + (j - i - 1)


@dataclass(frozen=True)
class Search:
    """The path A* found: its nodes' points (start to goal) and each edge's (length, shape)."""

    points: list[tuple[float, float]]
    steps: list[tuple[float, ArcShape | None]]
    nodes: int     # nodes the search reached
    edges: int     # edges it generated


_FIELDS = ('rank', 'other', 'here', 'there', 'there_circle', 'length')


@dataclass
class _Candidates:
    """Candidate tangents P-Q: rank, which end is on the circle in question (0: P), the other end's circle (-1
    for start or goal) and node (start or goal; None: the tangent's other end)."""

    P: FloatArray
    Q: FloatArray
    candidate: IntArray
    end: IntArray
    other_circle: IntArray
    other_node: int | None


@dataclass
class _Tangents:
    """Free candidate tangents: rank of the end on the circle in question, of the other end, both points."""

    rank: IntArray
    other: IntArray
    here: FloatArray       # (m, 2): the end on the circle
    there: FloatArray      # (m, 2)
    there_circle: IntArray  # circle of the other end, -1 for start or goal
    length: FloatArray


class _CircleNodes:
    """The free tangents' ends on one circle in angle order, and the arcs between neighbours (when free)."""

    def __init__(self, k: int, radius: float, center: tuple[float, float], tangents: _Tangents) -> None:
        cx, cy = center
        xs, ys = tangents.here[:, 0].tolist(), tangents.here[:, 1].tolist()
        angles = [wrap_angle(math.atan2(y - cy, x - cx)) for x, y in zip(xs, ys)]
        ranks = tangents.rank.tolist()
        order = sorted(range(len(ranks)), key=lambda t: (angles[t], ranks[t]))
        self.k, self.radius = k, radius
        self.ranks = [ranks[t] for t in order]
        self.angles = [angles[t] for t in order]
        self.points = [(xs[t], ys[t]) for t in order]
        self.position = {r: idx for idx, r in enumerate(self.ranks)}
        other, length = tangents.other.tolist(), tangents.length.tolist()
        there, circle = tangents.there.tolist(), tangents.there_circle.tolist()
        self.line = [(other[t], length[t], there[t], circle[t]) for t in order]
        self.arcs: dict[int, tuple[float, float] | None] = {}

    def arc(self, problem: TangentProblem, a: int) -> tuple[float, float] | None:
        """The counter-clockwise arc from node a to node a + 1 (mod m): (angle at a, sweep), None if blocked."""
        if a not in self.arcs:
            m = len(self.ranks)
            t0, t1 = self.angles[a], self.angles[(a + 1) % m]
            sweep = t1 - t0 if a + 1 < m else t1 + TWO_PI - t0
            self.arcs[a] = (t0, sweep) if problem.arc_free(self.k, t0, sweep) else None
        return self.arcs[a]

    def arc_edges(self, problem: TangentProblem, a: int) -> list[Edge]:
        """Node a's arcs to its neighbours: the shape seen from a (angle at a, signed sweep a -> neighbour)."""
        m = len(self.ranks)
        if m < 2:
            return []
        ahead, behind = self.arc(problem, a), self.arc(problem, (a - 1) % m)
        out: list[tuple[int, float, ArcShape]] = []
        if ahead is not None:
            out.append((self.ranks[(a + 1) % m], self.radius * ahead[1], (self.k, ahead[0], ahead[1])))
        if behind is not None:
            t0, sweep = behind
            out.append((self.ranks[(a - 1) % m], self.radius * sweep, (self.k, t0 + sweep, -sweep)))
        if m == 2 and len(out) == 2:
            # Both arcs join the same two nodes: the graph keeps the one added first (the arc from the node
            # first in angle order), unless the other is strictly shorter.
            first, second = (out[0], out[1]) if a == 0 else (out[1], out[0])
            return [second if second[1] < first[1] else first]
        return list(out)


class TangentGraph:
    """The tangent visibility graph of one (problem, start, goal), generated a node at a time."""

    def __init__(self, problem: TangentProblem, start: FloatArray, goal: FloatArray) -> None:
        self.problem = problem
        circles = problem.circles
        self.n = len(circles)
        self.centers = np.array([c.center for c in circles], dtype=float).reshape(-1, 2)
        self.radii = np.array([c.radius for c in circles], dtype=float)
        self.start, self.goal = start, goal
        self.point: dict[int, tuple[float, float]] = {START: (float(start[0]), float(start[1])),
                                                      GOAL: (float(goal[0]), float(goal[1]))}
        self.circle_of: dict[int, int] = {START: -1, GOAL: -1}
        self.on_circle: dict[int, _CircleNodes] = {}
        self.adjacency: dict[int, list[Edge]] = {}
        """The edges of every node asked for (made once)."""
        self.tabled = np.zeros(self.n, dtype=bool)
        """The circles whose nodes are made: their tangents to other circles are not tested again."""
        self.pending: dict[int, list[_Tangents]] = {}
        """For a circle not yet made: its free tangents to circles already made, seen from its end."""
        self._ends: dict[int, tuple[_Tangents, IntArray]] = {}
        """START, GOAL: its free tangents to every circle and each one's circle (made at the first need)."""

    # ------------------------------------------------------------------ candidate tangents
    def _end_candidates(self, point: FloatArray, base: int, ks: IntArray) -> _Candidates:
        """The tangents from a point (start: base 1, goal: base 1 + 2 n) to circles ks, the point as P."""
        on1, _, first, second = pair_tangents(self.centers[ks], self.radii[ks], np.tile(point, (len(ks), 1)),
                                              np.zeros(len(ks)), False)
        keep = np.stack([first, second], axis=1).ravel()
        Q = on1.reshape(-1, 2)[keep]
        candidate = (base + 2 * np.repeat(ks, 2) + np.tile([0, 1], len(ks)))[keep]
        return _Candidates(np.tile(point, (len(Q), 1)), Q, candidate, np.ones(len(Q), dtype=np.int64),
                           np.full(len(Q), -1), START if base == 1 else GOAL)

    def end_tangents(self, u: int, k: int | None = None) -> _Tangents:
        """The free tangents from START or GOAL (node u) to circle k, or to every circle when k is None.

        Made for every circle at once, the first time either is asked for: a circle's nodes need them, and
        one vectorised batch costs less than one per circle (the same numbers: each tangent is its own).
        """
        tangents, circle = self._all_end_tangents(u)
        if k is None:
            return tangents
        mine = circle == k
        return _Tangents(*(getattr(tangents, f)[mine] for f in _FIELDS))

    def _all_end_tangents(self, u: int) -> tuple[_Tangents, IntArray]:
        """end_tangents(u) and each one's circle, made once."""
        if u not in self._ends:
            base = 1 if u == START else 1 + 2 * self.n
            ks = np.arange(self.n)
            tangents = self._free(self._end_candidates(self.start if u == START else self.goal, base, ks))
            self._ends[u] = tangents, ((tangents.rank - 2) // 2 - base) // 2   # candidate base + 2 k + slot
        return self._ends[u]

    def _pair_candidates(self, k: int) -> _Candidates:
        """The common tangents of circle k with every circle not made yet, seen from k.

        Made with the end on the lower circle as P (as the whole graph makes them), so the same numbers.
        """
        n = self.n
        others = np.flatnonzero(~self.tabled)
        others = others[others != k]
        lo, hi = np.minimum(others, k), np.maximum(others, k)
        # Outer and inner in one batch: an inner tangent is the outer one of the second circle's radius negated
        # (pair_tangents' own definition), and every pair's numbers are its own.
        m = len(lo)
        on1, on2, first, second = pair_tangents(self.centers[np.concatenate([lo, lo])],
                                                self.radii[np.concatenate([lo, lo])],
                                                self.centers[np.concatenate([hi, hi])],
                                                np.concatenate([self.radii[hi], -self.radii[hi]]), False)
        parts = [(on1[:m], on2[:m], first[:m], second[:m]), (on1[m:], on2[m:], first[m:], second[m:])]
        # Per pair: outer first, outer second, inner first, inner second.
        keep = np.stack([parts[0][2], parts[0][3], parts[1][2], parts[1][3]], axis=1).ravel()
        P = np.stack([parts[0][0][:, 0], parts[0][0][:, 1], parts[1][0][:, 0], parts[1][0][:, 1]], axis=1)
        Q = np.stack([parts[0][1][:, 0], parts[0][1][:, 1], parts[1][1][:, 0], parts[1][1][:, 1]], axis=1)
        candidate = (1 + 4 * n + 4 * np.repeat(pair_rank(lo, hi, n), 4) + np.tile(np.arange(4), len(lo)))[keep]
        end = np.repeat((hi == k).astype(np.int64), 4)[keep]          # k's end: 0 on the lower circle
        other_circle = np.repeat(np.where(hi == k, lo, hi), 4)[keep]
        return _Candidates(P.reshape(-1, 2)[keep], Q.reshape(-1, 2)[keep], candidate, end, other_circle, None)

    def _free(self, c: _Candidates) -> _Tangents:
        """The free ones of candidate tangents, seen from their end on the circle in question."""
        free = self.problem.edges_free(c.P, c.Q)
        P, Q, candidate, end = c.P[free], c.Q[free], c.candidate[free], c.end[free]
        rank = 2 + 2 * candidate + end
        other = np.full(len(rank), c.other_node) if c.other_node is not None else 2 + 2 * candidate + (1 - end)
        at_q = end[:, None] == 1
        return _Tangents(rank, other, np.where(at_q, Q, P), np.where(at_q, P, Q), c.other_circle[free],
                         np.hypot(Q[:, 0] - P[:, 0], Q[:, 1] - P[:, 1]))

    def nodes_on(self, k: int) -> _CircleNodes:
        """Circle k's nodes: the ends of its free tangents to the start, the goal and every other circle."""
        if k not in self.on_circle:
            fresh = self._free(self._pair_candidates(k))
            parts = [self.end_tangents(START, k), self.end_tangents(GOAL, k), fresh, *self.pending.pop(k, [])]
            tangents = _Tangents(*(np.concatenate([getattr(p, f) for p in parts]) for f in _FIELDS))
            # The other circles will find these tangents here, seen from their end.
            order = np.argsort(fresh.there_circle, kind='stable')
            circles, first = np.unique(fresh.there_circle[order], return_index=True)
            for j, rows in zip(circles.tolist(), np.split(order, first[1:])):
                self.pending.setdefault(j, []).append(_Tangents(
                    fresh.other[rows], fresh.rank[rows], fresh.there[rows], fresh.here[rows],
                    np.full(len(rows), k), fresh.length[rows]))
            self.tabled[k] = True
            center = (float(self.centers[k, 0]), float(self.centers[k, 1]))
            self.on_circle[k] = _CircleNodes(k, float(self.radii[k]), center, tangents)
        return self.on_circle[k]

    # ------------------------------------------------------------------ a node's edges
    def edges(self, u: int) -> list[Edge]:
        """Node u's edges, seen from u: (node, length, shape)."""
        if u not in self.adjacency:
            self.adjacency[u] = list(self._end_edges(u) if u in (START, GOAL) else self._circle_edges(u))
        return self.adjacency[u]

    def _end_edges(self, u: int) -> Iterator[Edge]:
        """The start's (or the goal's) edges: the straight run, then its tangents to every circle."""
        if self.problem.edges_free(self.start[None], self.goal[None])[0]:
            (sx, sy), (gx, gy) = self.point[START], self.point[GOAL]
            yield GOAL if u == START else START, float(np.hypot(gx - sx, gy - sy)), None
        if self.n:
            tangents, circle = self._all_end_tangents(u)
            for rank, point, length, k in zip(tangents.rank.tolist(), tangents.here.tolist(),
                                              tangents.length.tolist(), circle.tolist()):
                self._know(rank, point, k)
                yield rank, length, None

    def _circle_edges(self, u: int) -> Iterator[Edge]:
        """A tangent point's edges: its tangent, then the free arcs to its neighbours on its circle."""
        nodes = self.nodes_on(self.circle_of[u])
        a = nodes.position[u]
        other, length, point, k = nodes.line[a]
        self._know(other, point, k)
        yield other, length, None
        for v, length, shape in nodes.arc_edges(self.problem, a):
            self._know(v, nodes.points[nodes.position[v]], nodes.k)
            yield v, length, shape

    def _know(self, rank: int, point: Sequence[float], circle: int) -> None:
        if rank not in self.point:
            self.point[rank] = (float(point[0]), float(point[1]))
            self.circle_of[rank] = circle


def search(problem: TangentProblem, start: FloatArray, goal: FloatArray) -> Search | None:
    """The shortest path from start to goal over the tangent graph; None when the goal cannot be reached."""
    graph = TangentGraph(problem, start, goal)
    if not _explore(graph):
        return None
    prev = _dijkstra(graph.adjacency)
    steps: list[tuple[float, ArcShape | None]] = []
    path = [GOAL]
    while path[-1] != START:
        u, w, shape = prev[path[-1]]
        steps.append((w, shape))
        path.append(u)
    return Search([graph.point[u] for u in reversed(path)], steps[::-1], len(graph.point),
                  sum(len(e) for e in graph.adjacency.values()))


def _explore(graph: TangentGraph) -> bool:
    """A* from the start until it reaches the goal (True) or finds it cannot (False).

    When the goal is reached, every node of every shortest path has had its edges made: such a node's
    estimate (distance so far plus the heuristic, which stays a slack below the rest of the path) is below
    the goal's distance, so it leaves the heap before the goal, with its final distance (a node is expanded
    again if a shorter way to it turns up).
    A walled-in goal would make A* explore everything the start reaches; so a flood from the goal (a step per
    FLOOD_EVERY A* steps, towards the start) runs alongside until it meets a node A* reached: when it runs out
    first, nothing joins them. (A walled-in goal among 1000 circles: A* alone took 19 s to give up, the whole
    graph 10 s, with the flood 0.1 s; in open worlds the flood adds about 15 %.)
    """
    gx, gy = graph.point[GOAL]
    sx, sy = graph.point[START]
    slack = HEURISTIC_SLACK * graph.problem.scale

    def estimate(node: int, distance: float) -> float:
        x, y = graph.point[node]
        return distance + max(0.0, math.hypot(gx - x, gy - y) * (1.0 - HEURISTIC_SLACK) - slack)

    dist = {START: 0.0}
    expanded_at: dict[int, float] = {}
    heap = [(estimate(START, 0.0), START)]
    flood: list[tuple[float, int]] | None = [(0.0, GOAL)]
    flooded = {GOAL}
    steps = 0
    while heap:
        _, u = heapq.heappop(heap)
        d = dist[u]
        if u == GOAL:
            return True
        if expanded_at.get(u, math.inf) > d:      # else a stale entry: u was expanded at this distance
            expanded_at[u] = d
            for v, w, _ in graph.edges(u):
                nd = d + w
                if nd < dist.get(v, math.inf):
                    dist[v] = nd
                    heapq.heappush(heap, (estimate(v, nd), v))
        steps += 1
        if flood is not None and steps % FLOOD_EVERY == 0:
            if not flood:
                return False                      # the goal's part of the graph holds no node A* reached
            _, f = heapq.heappop(flood)
            for v, _, _ in graph.edges(f):
                if v in dist:
                    flood = None                  # they meet: A* will reach the goal
                    break
                if v not in flooded:
                    flooded.add(v)
                    x, y = graph.point[v]
                    heapq.heappush(flood, (math.hypot(sx - x, sy - y), v))
    return False


def _dijkstra(edges: dict[int, list[Edge]]) -> dict[int, tuple[int, float, ArcShape | None]]:
    """Dijkstra from start to goal over the nodes whose edges were made: the predecessor of each node settled.

    All the nodes a shortest path can go through are here with all their edges, so it settles them in the
    order Dijkstra over the whole graph does (by distance, then rank) and picks the same path, also among
    paths of equal length (an equally short way into a node found later does not replace the first). Other
    nodes here either are farther or have no edges of their own: they change nothing on a shortest path.
    """
    dist = {START: 0.0}
    prev: dict[int, tuple[int, float, ArcShape | None]] = {}
    heap = [(0.0, START)]
    done = set()
    while heap:
        d, u = heapq.heappop(heap)
        if u in done:
            continue
        if u == GOAL:
            break
        done.add(u)
        for v, w, shape in edges.get(u, ()):
            nd = d + w
            if nd < dist.get(v, math.inf):
                dist[v], prev[v] = nd, (u, w, shape)
                heapq.heappush(heap, (nd, v))
    return prev
