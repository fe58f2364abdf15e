"""The lazy A* over the tangent graph (planning/shortest_path/tangent_search.py) finds the path the whole graph and
Dijkstra found (fastep_testing/optimal_eager.py): the same length, pieces and polyline, bit for bit, on many worlds."""

import math

import numpy as np
import pytest

from fastep_core.experiments.random_worlds import u_trap
from fastep_core.geometry import Circle, Segment
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.shortest_path.exact_path import parked_world
from fastep_core.planning.shortest_path.optimal import OptimalPath, shortest_path
from fastep_core.world import World
from fastep_testing.optimal_eager import shortest_path_eager


def assert_same(world: World, start, goal, clearance: float) -> OptimalPath | None:
    lazy = shortest_path(world, start, goal, clearance)
    eager = shortest_path_eager(world, start, goal, clearance)
    if eager is None:
        assert lazy is None
        return None
    assert lazy is not None
    assert lazy.length == eager.length
    assert lazy.pieces == eager.pieces
    assert np.array_equal(lazy.points, eager.points)
    assert (lazy.clearance, lazy.border) == (eager.clearance, eager.border)
    assert lazy.nodes <= eager.nodes
    return lazy


def random_obstacles(rng: np.random.Generator, n: int, side: float, origin: float = 0.0,
                     segments: float = 0.2) -> list[Circle | Segment]:
    out: list[Circle | Segment] = []
    for _ in range(n):
        a = origin + rng.uniform(0.0, side, 2)
        if rng.random() < segments:
            b = a + rng.normal(0.0, side / 8.0, 2)
            out.append(Segment((float(a[0]), float(a[1])), (float(b[0]), float(b[1]))))
        else:
            out.append(Circle((float(a[0]), float(a[1])), float(rng.uniform(0.02, 0.1) * side)))
    return out


def random_query(rng: np.random.Generator, n: int, side: float, origin: float = 0.0, segments: float = 0.2):
    world = World((origin, origin, origin + side, origin + side), tuple(random_obstacles(rng, n, side, origin,
                                                                                         segments)))
    start, goal = origin + rng.uniform(0.0, side, 2), origin + rng.uniform(0.0, side, 2)
    return world, start, goal, float(rng.uniform(0.002, 0.03) * side)


@pytest.mark.parametrize('seed', range(8))
def test_random_circles_and_walls(seed):
    rng = np.random.default_rng(seed)
    found = 0
    for _ in range(25):
        world, start, goal, clearance = random_query(rng, int(rng.integers(0, 50)), float(rng.choice([10, 50, 100])))
        found += assert_same(world, start, goal, clearance) is not None
    assert found > 0


@pytest.mark.parametrize('origin, side', [(0.0, 1e-3), (0.0, 1e-6), (1e6, 100.0), (-1e9, 1e4), (0.0, 1e12)])
def test_tiny_and_huge_coordinates(origin, side):
    rng = np.random.default_rng(int(abs(math.log10(side))))
    found = 0
    for _ in range(12):
        found += assert_same(*random_query(rng, int(rng.integers(5, 40)), side, origin)) is not None
    assert found > 0


@pytest.mark.parametrize('seed', range(4))
def test_u_traps_with_the_start_inside(seed):
    rng = np.random.default_rng(100 + seed)
    found = 0
    for _ in range(10):
        center = rng.uniform(15.0, 35.0, 2)
        facing = float(rng.uniform(-math.pi, math.pi))
        walls = [Segment(tuple(s['segment']['start']), tuple(s['segment']['end']))
                 for s in u_trap(center, float(rng.uniform(3.0, 8.0)), float(rng.uniform(3.0, 8.0)), facing)]
        world = World((0.0, 0.0, 50.0, 50.0), tuple(walls + random_obstacles(rng, 15, 50.0, segments=0.0)))
        away = center - 20.0 * np.array([math.cos(facing), math.sin(facing)])
        goal = np.clip(away, 1.0, 49.0)
        found += assert_same(world, center, goal, float(rng.uniform(0.3, 1.0))) is not None
    assert found > 0


def test_walled_in_goals_have_no_path_either_way():
    rng = np.random.default_rng(7)
    for _ in range(6):
        goal = rng.uniform(10.0, 40.0, 2)
        half = float(rng.uniform(1.5, 4.0))
        corners = [goal + half * np.array(c) for c in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        box = [Segment(tuple(corners[i]), tuple(corners[(i + 1) % 4])) for i in range(4)]
        ring = [Circle((float(goal[0] + 6 * math.cos(t)), float(goal[1] + 6 * math.sin(t))), 1.0)
                for t in np.linspace(0.0, 2 * math.pi, 20, endpoint=False)]
        world = World((0.0, 0.0, 50.0, 50.0), tuple(box + ring + random_obstacles(rng, 20, 50.0)))
        for start in (rng.uniform(0.0, 50.0, 2), goal + np.array([0.0, 4.5])):
            assert assert_same(world, start, goal, 0.4) is None


def test_start_and_goal_near_the_border():
    rng = np.random.default_rng(11)
    found = 0
    for _ in range(20):
        world = World((0.0, 0.0, 30.0, 20.0), tuple(random_obstacles(rng, 25, 20.0)))
        start = np.array([float(rng.uniform(0.0, 0.5)), float(rng.uniform(0.0, 20.0))])
        goal = np.array([float(rng.uniform(0.0, 30.0)), 20.0 - float(rng.uniform(0.0, 0.5))])
        found += assert_same(world, start, goal, float(rng.uniform(0.3, 1.0))) is not None
    assert found > 0


def test_symmetric_worlds_keep_the_same_choice_between_equal_paths():
    """Circles on the axis of start and goal, and a regular grid: ways round of exactly equal length."""
    on_axis = World((0.0, 0.0, 40.0, 20.0), (Circle((20.0, 10.0), 3.0),))
    assert_same(on_axis, (2.0, 10.0), (38.0, 10.0), 0.5)
    grid = World((0.0, 0.0, 40.0, 40.0), tuple(Circle((float(x), float(y)), 1.0)
                                               for x in range(5, 40, 5) for y in range(5, 40, 5)))
    for start, goal in (((2.5, 2.5), (37.5, 37.5)), ((2.5, 20.0), (37.5, 20.0)), ((7.5, 7.5), (32.5, 32.5))):
        assert_same(grid, start, goal, 0.6)
    twins = World((0.0, 0.0, 20.0, 20.0), (Segment((5.0, 5.0), (10.0, 10.0)), Segment((10.0, 10.0), (15.0, 5.0))))
    assert_same(twins, (10.0, 2.0), (10.0, 18.0), 0.5)


@pytest.mark.parametrize('seed', range(3))
def test_worlds_with_parked_robots(seed):
    """A crowd's escape paths: the obstacles plus every robot standing still as a circle."""
    rng = np.random.default_rng(200 + seed)
    params = PlannerParams()
    world = World((0.0, 0.0, 100.0, 100.0), tuple(Circle((float(x), float(y)), float(r)) for x, y, r in
                                                  zip(*rng.uniform(0.0, 100.0, (2, 50)), rng.uniform(0.5, 2.0, 50))))
    found = 0
    for _ in range(6):
        others = [OtherRobot(f'r{i}', (float(x), float(y))) for i, (x, y) in
                  enumerate(rng.uniform(1.0, 99.0, (int(rng.integers(30, 100)), 2)))]
        start, goal = rng.uniform(1.0, 99.0, 2), rng.uniform(1.0, 99.0, 2)
        parked = parked_world(world, others, goal, 0.5, params)
        assert parked is not None
        found += assert_same(parked, start, goal, 0.5 + params.clearance_margin) is not None
    assert found > 0
