"""Tests for fastep_core.dynamic_world: movers exactly as the formula of docs/scenarios.md says, and the planner's
map."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.dynamic_world import DynamicWorld, Motion, Movers, ObstacleSpec, map_generator
from fastep_core.geometry import Circle, Segment
from fastep_core.sensing.laser import LaserSpec


def reference_position(center: tuple[float, float], waypoints: list[tuple[float, float]], speed: float,
                       t: float) -> tuple[float, float]:
    """docs/scenarios.md, written out one mover and one time at a time: s = (speed t) mod 2L; arc s or 2L - s."""
    path = [center, *waypoints]
    lengths = [math.dist(a, b) for a, b in zip(path, path[1:])]
    total = sum(lengths)
    if total == 0.0:
        return center
    s = math.fmod(speed * t, 2 * total)
    arc = s if s <= total else 2 * total - s
    for (a, b), length in zip(zip(path, path[1:]), lengths):
        if arc <= length and length > 0.0:
            f = arc / length
            return a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])
        arc -= length
    return path[-1]


MOVERS = [
    (Circle((20.0, 25.0), 1.0), Motion(((30.0, 25.0), (30.0, 35.0)), 0.4)),
    (Circle((0.0, 0.0), 0.5), Motion(((3.0, 4.0),), 1.0)),                      # one waypoint: L = 5
    (Circle((1.0, 1.0), 0.5), Motion(((1.0, 1.0), (4.0, 1.0), (4.0, 1.0)), 2.0)),   # repeated points
    (Circle((7.0, 7.0), 0.5), Motion(((7.0, 7.0),), 1.0)),                      # a path of length 0
]


def test_positions_follow_the_formula_for_every_mover_at_once() -> None:
    movers = Movers([c for c, _ in MOVERS], [m for _, m in MOVERS])
    times = np.linspace(0.0, 200.0, 2001)
    got = movers.positions(times)
    assert got.shape == (len(times), len(MOVERS), 2)
    for k, (circle, motion) in enumerate(MOVERS):
        want = np.array([reference_position(circle.center, list(motion.waypoints), motion.speed, t) for t in times])
        np.testing.assert_allclose(got[:, k], want, atol=1e-9)


def test_ping_pong_landmarks() -> None:
    movers = Movers([MOVERS[1][0]], [MOVERS[1][1]])                    # (0,0) -> (3,4) at 1 m/s, L = 5
    for t, where in ((0.0, (0, 0)), (2.5, (1.5, 2.0)), (5.0, (3, 4)), (7.5, (1.5, 2.0)), (10.0, (0, 0)),
                     (15.0, (3, 4))):
        np.testing.assert_allclose(movers.positions(t)[0], where, atol=1e-12)


def test_velocities_point_along_the_segment_out_and_back() -> None:
    movers = Movers([c for c, _ in MOVERS[:2]], [m for _, m in MOVERS[:2]])
    v = movers.velocities(np.array([1.0, 30.0, 60.0]))
    np.testing.assert_allclose(v[0, 0], (0.4, 0.0))                   # out along the first segment
    np.testing.assert_allclose(v[1, 0], (0.0, 0.4))                   # t = 30: arc 12, on the second
    np.testing.assert_allclose(v[2, 0], (0.0, -0.4))                  # t = 60: arc 24 -> back, at 16
    np.testing.assert_allclose(v[0, 1], (0.6, 0.8))
    # Finite differences agree with the velocities away from the turning points.
    t = np.array([3.3, 41.7, 77.1])
    numeric = (movers.positions(t + 1e-6) - movers.positions(t - 1e-6)) / 2e-6
    np.testing.assert_allclose(movers.velocities(t), numeric, atol=1e-6)


def test_a_still_mover_has_no_velocity() -> None:
    movers = Movers([MOVERS[3][0]], [MOVERS[3][1]])
    np.testing.assert_array_equal(movers.velocities(np.array([0.0, 5.0])), np.zeros((2, 1, 2)))


def world(sigma: float = 0.5) -> DynamicWorld:
    return DynamicWorld((0.0, 0.0, 50.0, 50.0), (
        ObstacleSpec(Circle((20.0, 25.0), 1.0), Motion(((30.0, 25.0),), 0.4)),
        ObstacleSpec(Circle((35.0, 12.0), 2.0), known=False),
        ObstacleSpec(Segment((10.0, 30.0), (20.0, 30.0)), position_sigma=sigma),
        ObstacleSpec(Circle((40.0, 40.0), 2.0)),
        ObstacleSpec(Circle((5.0, 45.0), 1.0), Motion(((5.0, 40.0),), 0.4), known=False),
    ))


def test_the_truth_has_every_still_obstacle_and_every_mover() -> None:
    truth = world()
    assert truth.still.obstacle_list == (Circle((35.0, 12.0), 2.0), Segment((10.0, 30.0), (20.0, 30.0)),
                                         Circle((40.0, 40.0), 2.0))
    assert truth.movers.names == ('mover 0', 'mover 4')


def test_the_planner_map_has_known_obstacles_only_and_misplaces_by_the_seed() -> None:
    truth = world()
    first = truth.planner_map(map_generator(3))
    again = truth.planner_map(map_generator(3))
    other = truth.planner_map(map_generator(4))
    assert first.world == again.world and first.world != other.world
    shapes = first.world.obstacle_list
    assert len(shapes) == 2 and shapes[1] == Circle((40.0, 40.0), 2.0)   # no unknown circle, the wall moved
    wall = shapes[0]
    assert isinstance(wall, Segment) and wall != Segment((10.0, 30.0), (20.0, 30.0))
    errors = np.random.default_rng(np.random.SeedSequence(3, spawn_key=(0x6D6170,))).standard_normal(4) * 0.5
    np.testing.assert_allclose(np.subtract([*wall.start, *wall.end], [10, 30, 20, 30]), errors)
    assert first.movers.names == ('mover 0',)                          # the unknown mover is not on the map
    others = first.others(10.0)
    assert [o.name for o in others] == ['mover 0']
    assert others[0].position == (24.0, 25.0) and others[0].velocity == (0.4, 0.0) and others[0].radius == 1.0


def test_the_map_stream_is_not_a_swarm_stream() -> None:
    """Robots' swarms draw from SeedSequence(seed).spawn(n): none of them is the map's stream."""
    swarms = [np.random.default_rng(s).standard_normal(4) for s in np.random.SeedSequence(3).spawn(5)]
    mine = map_generator(3).standard_normal(4)
    assert all(not np.allclose(mine, s) for s in swarms)


def test_sigma_zero_leaves_the_map_exact() -> None:
    exact = world(sigma=0.0).planner_map(map_generator(3)).world
    assert exact.obstacle_list == (Segment((10.0, 30.0), (20.0, 30.0)), Circle((40.0, 40.0), 2.0))


@pytest.mark.parametrize('t', [0.0, 12.5, 50.0])
def test_a_misplaced_mover_keeps_one_error(t: float) -> None:
    truth = DynamicWorld((0.0, 0.0, 50.0, 50.0), (
        ObstacleSpec(Circle((20.0, 25.0), 1.0), Motion(((30.0, 25.0),), 0.4), position_sigma=1.0),))
    planner = truth.planner_map(map_generator(0))
    error = np.array(planner.others(t)[0].position) - truth.movers.positions(t)[0]
    np.testing.assert_allclose(error, planner.offsets[0])
    assert np.hypot(*error) > 0.0


def test_long_series_go_in_chunks_with_the_same_result(monkeypatch: pytest.MonkeyPatch) -> None:
    movers = Movers([c for c, _ in MOVERS], [m for _, m in MOVERS])
    times = np.linspace(0.0, 100.0, 999).reshape(27, 37)
    whole_p, whole_v = movers.positions(times), movers.velocities(times)
    monkeypatch.setattr('fastep_core.dynamic_world.LOOKUP_ELEMENTS', 50)
    np.testing.assert_array_equal(movers.positions(times), whole_p)
    np.testing.assert_array_equal(movers.velocities(times), whole_v)
    assert whole_p.shape == (27, 37, len(MOVERS), 2)


def test_a_scan_sees_the_truth_at_its_time() -> None:
    """Unknown obstacles, movers where they are at t, still ones where they really are, and other robots."""
    truth = world()
    spec = LaserSpec(range=20.0, fov=0.2, beams=3, noise=0.0)
    # From (35, 2) looking up (+y): the unknown circle at (35, 12) radius 2: 8 m.
    assert truth.scan(spec, (35.0, 2.0, math.pi / 2), 0.0).ranges[1] == pytest.approx(8.0)
    # From (24, 20) looking up: mover 0 is at (24, 25) at t = 10 (radius 1): 4 m; at t = 0 it is at (20, 25).
    assert truth.scan(spec, (24.0, 20.0, math.pi / 2), 10.0).ranges[1] == pytest.approx(4.0)
    assert math.isinf(truth.scan(spec, (24.0, 20.0, math.pi / 2), 0.0).ranges[1])
    # The misplaced wall y = 30 where it really is, whatever the map says; a robot in front of it first.
    assert truth.scan(spec, (15.0, 26.0, math.pi / 2), 0.0).ranges[1] == pytest.approx(4.0)
    seen = truth.scan(spec, (15.0, 26.0, math.pi / 2), 0.0, robots=(np.array([[15.0, 28.0]]), np.array([0.5])))
    assert seen.ranges[1] == pytest.approx(1.5)
