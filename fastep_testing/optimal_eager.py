"""The exact shortest path by building the whole tangent visibility graph: the reference A* is checked against.

This is how fastep_core/planning/shortest_path/optimal.py found its path before the lazy search
(planning/shortest_path/tangent_search.py): every candidate tangent among all circles is made and tested, every free one
and every free arc between neighbouring tangent points becomes a Python edge, and Dijkstra (heapq) runs over the whole
graph. It exists so that tests/fastep_core/planning/shortest_path/test_tangent_search.py can check that the lazy A*
finds the same paths (length, pieces and polyline, bit for bit) and benchmarks can compare their speed; the product
never calls it. It shares with optimal.py the problem (inflated circles, free-edge and free-arc tests), the tangents and
the polyline, so only the graph and its search differ.
"""

from __future__ import annotations

import heapq
import math
from typing import Iterator, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.planning.shortest_path.optimal import OptimalPath, _Problem, assemble, prepare
from fastep_core.planning.shortest_path.tangent_search import TWO_PI, ArcShape, pair_tangents, wrap_angle
from fastep_core.world import World

__all__ = ['shortest_path_eager']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


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


PAIRS_PER_TANGENT_BLOCK = 1 << 16
"""Circle pairs whose common tangents are made and tested at once (4 candidate edges each)."""


Candidates = tuple[FloatArray, FloatArray, IntArray, IntArray, IntArray, IntArray]


def _candidate_blocks(centers: FloatArray, radii: FloatArray, start: FloatArray,
                      goal: FloatArray) -> Iterator[Candidates]:
    """The candidate tangent edges in the order the graph numbers its nodes, in blocks of bounded size.

    Each block: P, Q (m, 2), the circle of each end (-1: start or goal) and the existing node of each end
    (-1: a new tangent point). First start's and goal's tangents to every circle, then every pair i < j:
    the outer tangents, then the inner ones.
    """
    n = len(radii)
    none = np.full(1, -1)
    yield start[None], goal[None], none, none, np.zeros(1, dtype=int), np.ones(1, dtype=int)   # the straight run
    for node, point in ((0, start), (1, goal)):
        if n == 0:
            break
        on1, _, first, second = pair_tangents(centers, radii, np.tile(point, (n, 1)), np.zeros(n), False)
        keep = np.stack([first, second], axis=1).ravel()
        k = np.repeat(np.arange(n), 2)[keep]
        Q = on1.reshape(-1, 2)[keep]
        yield np.tile(point, (len(Q), 1)), Q, np.full(len(Q), -1), k, np.full(len(Q), node), np.full(len(Q), -1)
    rows = max(1, PAIRS_PER_TANGENT_BLOCK // max(n, 1))
    for i0 in range(0, n - 1, rows):
        first_rows = np.arange(i0, min(i0 + rows, n - 1))
        counts = n - 1 - first_rows
        i = np.repeat(first_rows, counts)                    # i < j, row by row: the order of nested loops
        j = np.arange(len(i)) - np.repeat(np.cumsum(counts) - counts, counts) + i + 1
        parts = [pair_tangents(centers[i], radii[i], centers[j], radii[j], inner) for inner in (False, True)]
        # Per pair: outer first, outer second, inner first, inner second.
        keep = np.stack([parts[0][2], parts[0][3], parts[1][2], parts[1][3]], axis=1).ravel()
        P = np.stack([parts[0][0][:, 0], parts[0][0][:, 1], parts[1][0][:, 0], parts[1][0][:, 1]], axis=1)
        Q = np.stack([parts[0][1][:, 0], parts[0][1][:, 1], parts[1][1][:, 0], parts[1][1][:, 1]], axis=1)
        m = int(keep.sum())
        yield (P.reshape(-1, 2)[keep], Q.reshape(-1, 2)[keep], np.repeat(i, 4)[keep], np.repeat(j, 4)[keep],
               np.full(m, -1), np.full(m, -1))


def _build(problem: _Problem, start: np.ndarray, goal: np.ndarray) -> _Graph:
    graph = _Graph()
    s, g = graph.node(start, -1), graph.node(goal, -1)
    circles = problem.circles
    centers = np.array([c.center for c in circles], dtype=float).reshape(-1, 2)
    radii = np.array([c.radius for c in circles], dtype=float)
    on_circle: dict[int, list[int]] = {}
    for P, Q, K1, K2, N1, N2 in _candidate_blocks(centers, radii, start, goal):
        free = np.flatnonzero(problem.edges_free(P, Q))
        for p, q, ki, kj, ni, nj in zip(P[free], Q[free], K1[free].tolist(), K2[free].tolist(),
                                        N1[free].tolist(), N2[free].tolist()):
            u = ni if ni >= 0 else graph.node(p, ki)
            v = nj if nj >= 0 else graph.node(q, kj)
            for node, k in ((u, ki), (v, kj)):
                if k >= 0:                          # a new tangent point (start and goal lie on no circle)
                    on_circle.setdefault(k, []).append(node)
            graph.edge(u, v, float(np.hypot(*(q - p))), None)
    assert (s, g) == (0, 1)
    for k, nodes in on_circle.items():
        c = circles[k]
        angles = [(wrap_angle(math.atan2(graph.points[n][1] - c.center[1], graph.points[n][0] - c.center[0])), n)
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


def shortest_path_eager(world: World, start: Sequence[float] | FloatArray, goal: Sequence[float] | FloatArray,
                        clearance: float, *, spacing: float = 0.25) -> OptimalPath | None:
    """optimal.shortest_path by the whole graph and Dijkstra: the same arguments and answers."""
    prepared = prepare(world, start, goal, clearance, spacing)
    if prepared is None:
        return None
    problem, a, b = prepared
    if np.array_equal(a, b):
        return OptimalPath(0.0, np.array([a]), (), clearance, problem.border, 1, 0)
    graph = _build(problem, a, b)
    path = graph.dijkstra(0, 1)
    if path is None:
        return None
    points = [(float(graph.points[u][0]), float(graph.points[u][1])) for u in path]
    steps = [graph.adj[u][v] for u, v in zip(path[:-1], path[1:])]
    return assemble(problem, a, points, steps, spacing, len(graph.points), graph.n_edges)
