import numpy as np
import pytest

from fastep_core.geometry import Circle, Obstacles, Segment, point_segment_distance, segment_segment_distance


def test_point_segment_distance_projects_and_clips():
    a, b = np.array([0.0, 0.0]), np.array([10.0, 0.0])
    pts = np.array([[5.0, 3.0], [-4.0, 3.0], [13.0, -4.0]])
    assert point_segment_distance(pts, a, b) == pytest.approx([3.0, 5.0, 5.0])


def test_degenerate_segment_is_a_point():
    a = np.array([1.0, 1.0])
    assert point_segment_distance(np.array([4.0, 5.0]), a, a) == pytest.approx(5.0)


def test_segment_segment_crossing_parallel_and_apart():
    z = np.array
    assert segment_segment_distance(z([0, 0.]), z([2, 2.]), z([0, 2.]), z([2, 0.])) == 0.0
    assert segment_segment_distance(z([0, 0.]), z([2, 0.]), z([0, 1.]), z([2, 1.])) == pytest.approx(1.0)
    assert segment_segment_distance(z([0, 0.]), z([1, 0.]), z([3, 4.]), z([3, 9.])) == pytest.approx(np.hypot(2, 4))


def test_collinear_segments_apart_do_not_cross():
    """On one diagonal line a metre apart: the four cross products are rounding noise, and their signs once said the
    segments crossed (distance 0). path_clearance and fan_clearance agree on the gap."""
    p0, p1 = np.array([0.16710579185448293, 8.661835666543016]), np.array([-1.9100071270009744, 12.203157328052114])
    q0, q1 = np.array([-2.4159379358776403, 13.06573139248334]), np.array([-3.9337303625076383, 15.653453585777015])
    assert segment_segment_distance(p0, p1, q0, q1) == pytest.approx(1.0)
    wall = Obstacles([Segment(tuple(q0), tuple(q1))])
    assert wall.path_clearance(p0, p1) == pytest.approx(1.0) == wall.fan_clearance(p0, p1[None])[0]
    # Crossing at the smallest angle that still counts (sine 1e-8) and collinear overlapping: distance 0.
    assert segment_segment_distance(np.array([0.0, 0.0]), np.array([10.0, 1e-7]), np.array([0.0, 1e-7]),
                                    np.array([10.0, 0.0])) == 0.0
    assert segment_segment_distance(np.array([0.0, 0.0]), np.array([2.0, 2.0]), np.array([1.0, 1.0]),
                                    np.array([3.0, 3.0])) == pytest.approx(0.0, abs=1e-12)


def test_clearance_is_surface_distance_to_nearest_obstacle():
    obs = Obstacles([Circle((0.0, 0.0), 2.0), Segment((10.0, -5.0), (10.0, 5.0))])
    pts = np.array([[5.0, 0.0], [3.0, 0.0], [12.0, 0.0], [0.0, 1.0]])
    assert obs.clearance(pts) == pytest.approx([3.0, 1.0, 2.0, -1.0])
    assert obs.distances(pts).shape == (4, 2)


def test_no_obstacles_means_infinite_clearance():
    obs = Obstacles([])
    assert np.isinf(obs.clearance(np.zeros((3, 2)))).all()
    assert np.isinf(obs.path_clearance(np.zeros(2), np.ones((3, 2)))).all()


def test_path_clearance_and_blocking():
    obs = Obstacles([Circle((5.0, 0.0), 1.0), Segment((0.0, 3.0), (10.0, 3.0))])
    a = np.array([0.0, 0.0])
    ends = np.array([[10.0, 0.0], [10.0, 1.5], [0.0, -5.0], [5.0, 6.0]])
    d = obs.path_distances(a, ends)
    assert d[0, 0] == pytest.approx(-1.0)                     # through the circle centre
    assert d[2] == pytest.approx([np.hypot(5, 0) - 1.0, 3.0])  # away from both
    assert d[3, 1] == 0.0                                      # crosses the wall
    blocks = obs.blocking(a, np.array([10.0, 1.5]), within=0.5)
    assert blocks.tolist() == [True, False]


def test_vectorised_clearance_matches_pointwise():
    rng = np.random.default_rng(3)
    obs = Obstacles([Circle(tuple(c), r) for c, r in zip(rng.uniform(0, 50, (6, 2)), rng.uniform(1, 4, 6))]
                    + [Segment(tuple(s), tuple(e))
                       for s, e in zip(rng.uniform(0, 50, (3, 2)), rng.uniform(0, 50, (3, 2)))])
    pts = rng.uniform(0, 50, (40, 2))
    assert obs.clearance(pts) == pytest.approx([float(obs.clearance(p)) for p in pts])
    b = rng.uniform(0, 50, (40, 2))
    assert obs.path_clearance(pts[0], b) == pytest.approx([float(obs.path_clearance(pts[0], q)) for q in b])


def test_fan_clearance_equals_path_clearance():
    rng = np.random.default_rng(11)
    obs = Obstacles([Circle(tuple(c), r) for c, r in zip(rng.uniform(0, 20, (5, 2)), rng.uniform(0.5, 3, 5))]
                    + [Segment(tuple(s), tuple(e))
                       for s, e in zip(rng.uniform(0, 20, (4, 2)), rng.uniform(0, 20, (4, 2)))])
    origin = np.array([10.0, 10.0])
    ends = np.vstack([rng.uniform(0, 20, (500, 2)), origin[None, :]])
    assert obs.fan_clearance(origin, ends) == pytest.approx(obs.path_clearance(origin, ends), abs=1e-9)
    assert (obs.fan_clearance(origin, ends) == 0.0).any()   # some runs cross a wall


def test_distance_rows_is_distances_transposed():
    rng = np.random.default_rng(5)
    obs = Obstacles([Circle((3.0, 4.0), 1.0), Segment((0.0, 0.0), (5.0, 1.0)), Segment((2.0, 2.0), (2.0, 2.0))])
    pts = rng.uniform(-5, 10, (50, 2))
    assert obs.distance_rows(pts[:, 0], pts[:, 1]) == pytest.approx(obs.distances(pts).T)


def test_near_is_clearance_below_a_distance():
    # Obstacles.near tests only the (point, obstacle) pairs whose bounding boxes come close: the same answer as
    # clearance < within, also on a grid where points lie exactly at the distance, and with a nan point.
    rng = np.random.default_rng(5)
    for trial in range(300):
        grid = trial % 2 == 1
        n_c, n_s, m = rng.integers(0, 15), rng.integers(0, 30), rng.integers(0, 200)
        if grid:
            items = [Circle(tuple(map(float, c)), float(r)) for c, r in zip(rng.integers(-5, 5, (n_c, 2)),
                                                                            rng.integers(0, 3, n_c))]
            items += [Segment(tuple(map(float, s)), tuple(map(float, s + d)))
                      for s, d in zip(rng.integers(-5, 5, (n_s, 2)), rng.integers(-2, 3, (n_s, 2)))]
            pts = rng.integers(-6, 6, (m, 2)) + rng.choice([0.0, 0.12, -0.12, 0.5], (m, 2))
        else:
            items = [Circle(tuple(map(float, c)), float(r)) for c, r in zip(rng.uniform(-10, 10, (n_c, 2)),
                                                                            rng.uniform(0, 2, n_c))]
            items += [Segment(tuple(map(float, s)), tuple(map(float, s + d)))
                      for s, d in zip(rng.uniform(-10, 10, (n_s, 2)), rng.uniform(-1, 1, (n_s, 2)))]
            pts = rng.uniform(-11, 11, (m, 2))
            if m:
                pts[0] = np.nan
        obs = Obstacles(items)
        within = float(rng.choice([0.12, 0.0, -0.1, 0.5, 3.0]))
        want = obs.clearance(pts) < within if len(obs) else np.zeros(m, dtype=bool)
        np.testing.assert_array_equal(obs.near(pts, within), want)
