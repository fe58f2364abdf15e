"""The exact shortest path: closed-form answers, bounds from polygon visibility graphs, and the property that no
simulated run can beat it."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from fastep_core.errors import ParameterError
from fastep_core.geometry import Circle, Segment
from fastep_core.planning.algorithms import ALGORITHMS
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.scenario import builtin_names, load_scenario, parse_scenario
from fastep_core.simulator import simulate
from fastep_core.world import World


def world(*obstacles, workspace=(0.0, 0.0, 50.0, 50.0)):
    return World.from_obstacles(workspace, obstacles)


def dense(points, step=0.005):
    """Points along a polyline at most `step` apart."""
    out = [points[:1]]
    for a, b in zip(points[:-1], points[1:]):
        k = max(1, int(math.ceil(np.hypot(*(b - a)) / step)))
        out.append(a + np.linspace(0.0, 1.0, k + 1)[1:, None] * (b - a))
    return np.concatenate(out)


def assert_keeps_clearance(w, path, r):
    for pts in (dense(path.points), path.sample(0.005)):
        assert w.obstacles.clearance(pts).min() >= r - 1e-6
        assert w.wall_distance(pts).min() >= path.border - 1e-6


def test_free_space_is_the_straight_line():
    path = shortest_path(world(Circle((40.0, 40.0), 2.0)), (5.0, 5.0), (30.0, 10.0), 0.7)
    assert path.length == pytest.approx(math.hypot(25.0, 5.0), abs=1e-12)
    np.testing.assert_allclose(path.points, [[5.0, 5.0], [30.0, 10.0]])


@pytest.mark.parametrize('D, radius, r', [(10.0, 3.0, 0.5), (6.0, 1.0, 0.7), (20.0, 4.5, 0.2)])
def test_one_circle_on_the_line_two_tangents_and_an_arc(D, radius, r):
    centre = (25.0, 25.0)
    w = world(Circle(centre, radius))
    path = shortest_path(w, (25.0 - D, 25.0), (25.0 + D, 25.0), r)
    R = radius + r
    expected = 2.0 * math.sqrt(D * D - R * R) + R * (math.pi - 2.0 * math.acos(R / D))
    assert path.length == pytest.approx(expected, rel=1e-12)
    assert [p.kind for p in path.pieces] == ['line', 'arc', 'line']
    assert path.polyline_length >= path.length
    assert path.polyline_length <= path.length * 1.001
    assert_keeps_clearance(w, path, r)


def test_a_wall_is_passed_around_its_nearer_end():
    # Wall x = 10 from y = 4 to y = 14; start and goal at y = 10: the top end is 4 m off the line, the bottom 6 m.
    w = world(Segment((10.0, 4.0), (10.0, 14.0)), workspace=(0.0, 0.0, 20.0, 20.0))
    r = 0.5
    path = shortest_path(w, (5.0, 10.0), (15.0, 10.0), r)
    D = math.hypot(5.0, 4.0)
    gamma = 2.0 * math.atan2(5.0, 4.0)           # angle at the wall end between the directions to start and goal
    expected = 2.0 * math.sqrt(D * D - r * r) + r * (2.0 * math.pi - gamma - 2.0 * math.acos(r / D))
    assert path.length == pytest.approx(expected, rel=1e-12)
    assert path.points[:, 1].max() > 14.0
    assert_keeps_clearance(w, path, r)


def test_a_long_wall_is_skirted_along_its_flat_side():
    # Start and goal 0.2 m above the line of a 30 m wall, beyond its ends: the path climbs onto the capsule's
    # flat side (0.5 m above the wall) around one end cap and leaves it around the other.
    w = world(Segment((10.0, 10.0), (40.0, 10.0)))
    r = 0.5
    path = shortest_path(w, (8.0, 10.2), (42.0, 10.2), r)
    D = math.hypot(2.0, 0.2)
    direction = math.atan2(0.2, -2.0)                  # from the left end to the start
    arc = r * (direction - math.acos(r / D) - math.pi / 2.0)
    expected = 2.0 * (math.sqrt(D * D - r * r) + arc) + 30.0
    assert path.length == pytest.approx(expected, rel=1e-12)
    assert [p.kind for p in path.pieces] == ['line', 'arc', 'line', 'arc', 'line']
    assert_keeps_clearance(w, path, r)


def test_an_enclosed_goal_has_no_path():
    box = [Segment((20.0, 20.0), (30.0, 20.0)), Segment((30.0, 20.0), (30.0, 30.0)),
           Segment((30.0, 30.0), (20.0, 30.0)), Segment((20.0, 30.0), (20.0, 20.0))]
    assert shortest_path(world(*box), (5.0, 5.0), (25.0, 25.0), 0.7) is None


def test_a_gap_narrower_than_twice_the_clearance_is_closed():
    # Two circles 1.0 m apart: open for r = 0.4, closed for r = 0.6 (the path must go around both).
    w = world(Circle((25.0, 22.0), 2.0), Circle((25.0, 27.0), 2.0))
    narrow = shortest_path(w, (15.0, 24.5), (35.0, 24.5), 0.4)
    wide = shortest_path(w, (15.0, 24.5), (35.0, 24.5), 0.6)
    assert narrow.length == pytest.approx(20.0)
    assert wide.length > 21.0
    assert_keeps_clearance(w, wide, 0.6)


def test_the_border_is_respected():
    # A circle almost touching the bottom border: the path cannot slip underneath it.
    w = world(Circle((25.0, 3.0), 2.5), workspace=(0.0, 0.0, 50.0, 50.0))
    path = shortest_path(w, (10.0, 2.0), (40.0, 2.0), 0.5)
    assert path.points[:, 1].max() > 6.0
    assert_keeps_clearance(w, path, 0.5)


def test_start_closer_than_the_clearance_has_no_path():
    w = world(Circle((10.0, 10.0), 2.0))
    assert shortest_path(w, (12.5, 10.0), (30.0, 30.0), 0.7) is None
    assert shortest_path(w, (12.5, 10.0), (30.0, 30.0), 0.4) is not None


def test_bad_arguments_raise_a_parameter_error_that_is_still_a_value_error():
    with pytest.raises(ParameterError, match='clearance must be'):
        shortest_path(world(), (1.0, 1.0), (2.0, 2.0), 0.0)
    with pytest.raises(ParameterError, match='spacing must be'):
        shortest_path(world(), (1.0, 1.0), (2.0, 2.0), 0.5, spacing=-1.0)
    with pytest.raises(ValueError, match='start and goal must be finite'):
        shortest_path(world(), (math.nan, 1.0), (2.0, 2.0), 0.5)


@pytest.mark.parametrize('name', builtin_names())
def test_builtin_paths_keep_the_clearance_and_beat_nothing_straighter(name):
    scenario = load_scenario(name)
    for spec in scenario.robots:
        r = spec.radius + scenario.planner.clearance_margin
        path = shortest_path(scenario.world, spec.start[:2], spec.goal, r)
        assert path is not None
        assert path.length >= math.dist(spec.start[:2], spec.goal) - 1e-9
        assert_keeps_clearance(scenario.world, path, r)
        np.testing.assert_allclose(path.points[0], spec.start[:2])
        np.testing.assert_allclose(path.points[-1], spec.goal)


# ------------------------------------------------------------------------- bounds from polygon visibility graphs

def _hull(points):
    """Convex hull (counter-clockwise, Andrew's monotone chain)."""
    pts = sorted(map(tuple, points))

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def _polygons(w, r, n, outer):
    """Each inflated obstacle as a convex polygon inside it (outer=False) or around it (outer=True)."""
    t = 2.0 * np.pi * (np.arange(n) + 0.5) / n
    unit = np.column_stack([np.cos(t), np.sin(t)]) / (np.cos(np.pi / n) if outer else 1.0)
    polys = []
    for o in w.obstacle_list:
        if isinstance(o, Circle):
            polys.append(np.array(o.center) + (o.radius + r) * unit)
        else:
            polys.append(_hull(np.vstack([np.array(o.start) + r * unit, np.array(o.end) + r * unit])))
    return polys


def _crosses_interior(P, Q, poly, eps=1e-9):
    """Which segments P[i]-Q[i] pass through the open convex polygon (separating axis test)."""
    edges = np.roll(poly, -1, axis=0) - poly
    normals = np.column_stack([edges[:, 1], -edges[:, 0]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    proj = poly @ normals.T
    pp, qp = P @ normals.T, Q @ normals.T
    # The closed projection [lo, hi] of the segment meets the open projection of the polygon on every axis.
    hit = ((np.maximum(pp, qp) > proj.min(axis=0) + eps) & (np.minimum(pp, qp) < proj.max(axis=0) - eps)).all(axis=1)
    d = Q - P
    m = np.column_stack([-d[:, 1], d[:, 0]])
    m /= np.maximum(np.linalg.norm(m, axis=1), 1e-300)[:, None]
    pm = np.einsum('ij,ij->i', P, m)
    vm = poly @ m.T
    return hit & (vm.min(axis=0) + eps < pm) & (pm < vm.max(axis=0) - eps)


def _polygon_shortest(start, goal, polys):
    from scipy.sparse.csgraph import dijkstra
    nodes = np.vstack([start, goal, *polys])
    i, j = np.triu_indices(len(nodes), 1)
    P, Q = nodes[i], nodes[j]
    free = np.ones(len(i), dtype=bool)
    for poly in polys:
        free &= ~_crosses_interior(P, Q, poly)
    n = len(nodes)
    weights = np.zeros((n, n))
    length = np.hypot(*(Q - P).T)
    weights[i[free], j[free]] = np.maximum(length[free], 1e-12)
    dist = dijkstra(weights, directed=False, indices=0)
    return dist[1]


@pytest.mark.parametrize('seed', range(6))
def test_exact_length_lies_between_polygon_bounds(seed):
    rng = np.random.default_rng(seed)
    r = 0.5
    while True:
        obstacles = [Circle(tuple(rng.uniform(12.0, 38.0, 2)), float(rng.uniform(1.0, 4.0))) for _ in range(5)]
        if seed % 2:
            a = rng.uniform(12.0, 38.0, 2)
            obstacles.append(Segment(tuple(a), tuple(a + rng.uniform(-8.0, 8.0, 2))))
        w = world(*obstacles)
        start, goal = np.array([5.0, rng.uniform(5.0, 45.0)]), np.array([45.0, rng.uniform(5.0, 45.0)])
        path = shortest_path(w, start, goal, r)
        if path is not None:
            break
    lower = _polygon_shortest(start, goal, _polygons(w, r, 64, outer=False))
    upper = _polygon_shortest(start, goal, _polygons(w, r, 64, outer=True))
    assert lower - 1e-6 <= path.length <= upper + 1e-6
    assert upper - lower < 0.01 * path.length      # the bounds are tight enough to mean something
    assert_keeps_clearance(w, path, r)


# ------------------------------------------------------------------------- no simulated run beats it

circle_fields = st.lists(
    st.tuples(st.floats(12.0, 38.0), st.floats(10.0, 40.0), st.floats(1.0, 4.0)), min_size=1, max_size=6)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(circles=circle_fields, y0=st.floats(8.0, 42.0), y1=st.floats(8.0, 42.0))
def test_no_simulated_run_is_shorter_than_the_optimum(circles, y0, y1):
    doc = {'workspace': [0, 0, 50, 50],
           'obstacles': [{'circle': {'center': [x, y], 'radius': rad}} for x, y, rad in circles],
           'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [5.0, y0], 'goal': [45.0, y1],
                       'radius': 0.5}]}
    scenario = parse_scenario(doc, default_name='random')
    spec = scenario.robots[0]
    line = math.dist(spec.start, spec.goal)
    # The shortest path that merely avoids collision (clearance = radius) bounds every collision-free run;
    # the run may stop goal_tolerance short of the goal.
    bound = shortest_path(scenario.world, spec.start, spec.goal, spec.radius)
    assume(bound is not None)
    assert bound.length >= line - 1e-9
    reference = shortest_path(scenario.world, spec.start, spec.goal, spec.radius + scenario.planner.clearance_margin)
    if reference is not None:
        assert reference.length >= bound.length - 1e-9
    for algorithm in ALGORITHMS:
        robot = simulate(scenario, algorithm, 0).robots[0]
        if robot.reached and not robot.collided:
            assert bound.length <= robot.path_length + scenario.planner.goal_tolerance + 1e-3, algorithm


# ------------------------------------------------------------------------- the navigator that drives it

def test_optimal_navigator_drives_the_exact_path():
    scenario = load_scenario('table2_s2')
    spec = scenario.robots[0]
    exact = shortest_path(scenario.world, spec.start, spec.goal, spec.radius + scenario.planner.clearance_margin)
    robot = simulate(scenario, 'optimal', 0).robots[0]
    assert robot.reached and not robot.collided
    assert robot.activations == 1
    assert abs(robot.path_length - exact.length) < 0.01 * exact.length
    assert robot.min_clearance > 0.05          # corner cutting eats only part of the 0.2 m margin


def test_optimal_navigator_lets_the_swarm_break_a_head_on_hold():
    # case_study_2: two robots swap corners along one diagonal; the exact paths meet head-on.
    run = simulate(load_scenario('case_study_2'), 'optimal', 0)
    assert all(r.reached and not r.collided for r in run.robots)
    assert all(r.activations > 1 for r in run.robots)        # a swarm step, then the exact path again


def test_optimal_navigator_fails_cleanly_without_a_path():
    doc = {'workspace': [0, 0, 50, 50],
           'obstacles': [{'segment': {'start': a, 'end': b}} for a, b in
                         (([20, 20], [30, 20]), ([30, 20], [30, 30]), ([30, 30], [20, 30]), ([20, 30], [20, 20]))],
           'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [5, 5], 'goal': [25, 25], 'radius': 0.5}]}
    robot = simulate(parse_scenario(doc), 'optimal', 0).robots[0]
    assert not robot.reached and not robot.collided
    assert robot.status.startswith('failed: no valid path')


def test_fastep_sim_accepts_the_optimal_algorithm(capsys):
    from msg_tools.sim_cli import main
    assert main(['table2_s3', '--algorithm', 'optimal']) == 0
    assert 'arrived' in capsys.readouterr().out


# ------------------------------------------------------------------ many obstacles (issue 15, item 4)

def _cluttered(n: int, side: float, seed: int, segments: int = 0) -> World:
    rng = np.random.default_rng(seed)
    obstacles: list[Circle | Segment] = []
    while len(obstacles) < n:
        c, r = rng.uniform(0.0, side, 2), float(rng.uniform(0.2, 0.8))
        if min(math.dist(c, (2.0, 2.0)), math.dist(c, (side - 2.0, side - 2.0))) > r + 1.5:
            obstacles.append(Circle((float(c[0]), float(c[1])), r))
    obstacles += [Segment(tuple(rng.uniform(0.0, side, 2)), tuple(rng.uniform(0.0, side, 2)))
                  for _ in range(segments)]
    return World((0.0, 0.0, side, side), tuple(obstacles))


def test_hundreds_of_circles_stay_within_bounded_memory():
    """Every candidate edge against every obstacle at once took O(N^3) memory: 250 circles about 1.3 GB."""
    import tracemalloc
    world = _cluttered(250, 50.0, seed=0)
    tracemalloc.start()
    try:
        path = shortest_path(world, (2.0, 2.0), (48.0, 48.0), 0.6)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert path is not None
    assert peak < 300e6


@pytest.mark.parametrize('seed', range(4))
def test_the_grid_decides_every_edge_as_the_full_distance_matrix_does(seed):
    """The near-obstacle test (ObstacleGrid) must take the same decision, bit for bit, as path_clearance."""
    from fastep_core.planning.shortest_path.optimal import TOL, _Problem
    world = _cluttered(60, 30.0, seed, segments=6)
    rng = np.random.default_rng(seed)
    clearance = float(rng.uniform(0.1, 1.0))
    problem = _Problem(world, clearance, clearance)
    P, Q = rng.uniform(-1.0, 31.0, (4000, 2)), rng.uniform(-1.0, 31.0, (4000, 2))
    Q[:1000] = P[:1000] + rng.normal(0.0, 1.0, (1000, 2))            # short edges as well as long ones
    inside = problem.inside(P) & problem.inside(Q)
    expected = inside & (world.obstacles.path_clearance(P, Q) >= clearance - TOL)
    assert 0 < expected.sum() < inside.sum()
    assert np.array_equal(problem.edges_free(P, Q), expected)


def _cell_outlines(occupied, cell):
    """Each occupied cell as its four sides: corners shared by up to eight walls, most blocked all round."""
    walls = []
    for row, col in zip(*np.nonzero(occupied)):
        x0, y0, x1, y1 = col * cell, row * cell, (col + 1) * cell, (row + 1) * cell
        corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        walls += [Segment(corners[k], corners[(k + 1) % 4]) for k in range(4)]
    return walls


@pytest.mark.parametrize('seed', range(6))
def test_leaving_out_caps_blocked_all_round_finds_the_same_path(seed, monkeypatch):
    """The search leaves out a corner's repeated caps and the caps no point of which is free. On worlds of
    rasterised blobs (most caps left out) it must find the very path the search with every cap finds."""
    from fastep_core.planning.shortest_path import optimal
    rng = np.random.default_rng(seed)
    blobs = rng.random((12, 16)) < 0.22
    blobs[:2, :2] = blobs[-2:, -2:] = False        # room round the start and the goal
    w = World((0.0, 0.0, 16.0, 12.0), tuple(_cell_outlines(blobs, 1.0)) +
              (Circle((float(rng.uniform(4, 12)), float(rng.uniform(3, 9))), 0.3),))
    start, goal, r = (0.5, 0.5), (15.5, 11.5), float(rng.uniform(0.15, 0.45))
    fewer = shortest_path(w, start, goal, r)
    kept = []
    original = optimal._Problem._add_caps
    monkeypatch.setattr(optimal._Problem, '_add_caps',
                        lambda self, caps: (kept.append(len(caps)), self.circles.extend(caps)))
    every = shortest_path(w, start, goal, r)
    monkeypatch.setattr(optimal._Problem, '_add_caps', original)
    assert kept and len(optimal._Problem(w, r, r).circles) < kept[0] / 3
    assert (fewer is None) == (every is None)
    if every is not None:
        assert fewer is not None
        assert fewer.length == every.length
        assert np.array_equal(fewer.points, every.points)
