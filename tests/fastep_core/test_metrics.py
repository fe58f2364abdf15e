"""trajectory_margins: clearance to obstacles and to other robots along trajectories, with one time alignment."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.geometry import Circle, Obstacles, Segment
from fastep_core.metrics import positions_at, trajectory_margins

NONE = Obstacles()


def test_obstacle_margin_is_the_closest_sample_to_any_surface_minus_the_radius() -> None:
    obstacles = Obstacles([Circle((5.0, 0.0), 1.0), Segment((0.0, 3.0), (10.0, 3.0))])
    # Rows of a tractor-trailer (t, x, y, theta0, theta1): the headings are ignored.
    track = [[0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 3.0, 0.0, 0.1, 0.0], [2.0, 6.0, 2.2, 0.2, 0.1]]
    margins = trajectory_margins([track], [0.5], obstacles)
    # (3, 0) is 1 from the circle's surface, (6, 2.2) 0.8 from the wall (and 1.42 from the circle).
    assert margins.obstacles[0] == pytest.approx(0.8 - 0.5)
    assert margins.robots[0] == math.inf and margins.overall[0] == margins.obstacles[0]


def test_robots_on_the_same_clock_are_compared_sample_by_sample() -> None:
    a = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 2.0, 0.0]]
    b = [[0.0, 2.0, 0.0], [1.0, 2.0, 0.5], [2.0, 2.0, 3.0]]
    margins = trajectory_margins([a, b], [0.2, 0.1], NONE)
    # Samples 1 apart in time: closest at t = 1 (distance hypot(1, 0.5)), not where the paths cross (t = 2 for
    # a, t = 0 for b): the robots were never both at (2, 0).
    assert margins.robots == pytest.approx([math.hypot(1.0, 0.5) - 0.3] * 2)
    assert np.all(np.isinf(margins.obstacles))


def test_robots_sampled_at_different_times_are_compared_at_every_sample_of_either() -> None:
    a = [[0.0, 0.0, 0.0], [2.0, 2.0, 0.0]]          # drives along y = 0, sampled at 0 and 2 s
    b = [[1.0, 1.0, 1.0]]                           # sampled once, at 1 s, while a was at (1, 0)
    margins = trajectory_margins([a, b], [0.25, 0.25], NONE)
    assert margins.robots == pytest.approx([0.5, 0.5])


def test_before_its_first_and_after_its_last_sample_a_robot_is_held_in_place() -> None:
    track = np.array([[1.0, 0.0, 0.0], [2.0, 1.0, 0.0]])
    assert positions_at(track, np.array([0.0, 1.5, 5.0])).tolist() == [[0.0, 0.0], [0.5, 0.0], [1.0, 0.0]]
    early = [[0.0, 0.0, 1.0]]                       # one sample at t = 0: it stays at (0, 1)
    late = [[3.0, 5.0, 0.0], [4.0, 0.0, 0.9]]       # samples from t = 3 on: at (5, 0) until then
    margins = trajectory_margins([early, late], [0.5, 0.5], NONE)
    assert margins.robots == pytest.approx([-0.9, -0.9])    # at t = 4 0.1 apart: the discs overlap, a collision


def test_nothing_to_measure_against_is_infinite() -> None:
    obstacles = Obstacles([Circle((0.0, 0.0), 1.0)])
    margins = trajectory_margins([[], [[0.0, 3.0, 0.0]], np.zeros((0, 5))], [0.5, 0.5, 0.5], obstacles)
    assert margins.obstacles.tolist() == [math.inf, 1.5, math.inf]
    assert margins.robots.tolist() == [math.inf] * 3
    assert trajectory_margins([], [], obstacles).overall.size == 0
    with pytest.raises(ValueError, match='2 tracks but 1 radii'):
        trajectory_margins([[], []], [0.5], obstacles)


def test_many_samples_are_measured_in_chunks_with_the_same_result() -> None:
    obstacles = Obstacles([Circle((float(k), 0.0), 0.3) for k in range(20)])
    t = np.linspace(0.0, 100.0, 50_001)
    track = np.column_stack([t, 20.0 * t / 100.0, 1.0 + np.sin(t)])
    expected = float(obstacles.clearance(track[:, 1:3]).min()) - 0.5
    assert trajectory_margins([track], [0.5], obstacles).obstacles[0] == expected


def test_a_robot_with_a_footprint_is_judged_by_its_outline_at_each_heading() -> None:
    from fastep_core.footprint import Footprint

    box = Footprint.parse([[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]])
    # A cylinder 0.3 m from base_link along the box's diagonal: clear of the 0.22 m circle, inside the box's corner.
    obstacles = Obstacles([Circle((0.3 * math.cos(0.7), 0.3 * math.sin(0.7)), 0.05)])
    corner = [[0.0, 0.0, 0.0, 0.0]]
    side = [[0.0, 0.0, 0.0, math.pi / 2]]
    as_circle = trajectory_margins([corner], [0.22], obstacles)
    as_box = trajectory_margins([corner, side], [box.radius, box.radius], obstacles, footprints=[box, box])
    assert as_circle.obstacles[0] > 0.0 and as_box.obstacles[0] < 0.0
    assert as_box.obstacles[0] == pytest.approx(float(box.clearance([0.0, 0.0, 0.0], obstacles)))
    assert as_box.obstacles[1] == pytest.approx(0.3 * math.cos(0.7) - 0.215 - 0.05)
    # Robot against robot stays the circles (their radii).
    assert as_box.robots == pytest.approx([-2 * box.radius] * 2)
    # Circle robots beside one with a footprint: what they were without it.
    mixed = trajectory_margins([[[0.0, 3.0, 0.0]], corner], [0.22, box.radius], obstacles, footprints=[None, box])
    alone = trajectory_margins([[[0.0, 3.0, 0.0]]], [0.22], obstacles)
    assert mixed.obstacles[0] == alone.obstacles[0]
    with pytest.raises(ValueError, match='no heading'):
        trajectory_margins([[[0.0, 0.0, 0.0]]], [box.radius], obstacles, footprints=[box])
    with pytest.raises(ValueError, match='1 tracks but 2 footprints'):
        trajectory_margins([corner], [box.radius], obstacles, footprints=[box, None])


def test_a_footprint_meets_the_movers_where_they_are() -> None:
    from fastep_core.dynamic_world import DynamicWorld, Motion, ObstacleSpec
    from fastep_core.footprint import Footprint

    box = Footprint.parse([[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]])
    # A mover of radius 0.1 passing from (2, 0) toward (-2, 0) at 1 m/s: at t = 1.6 its centre is at x = 0.4.
    movers = DynamicWorld((-5.0, -5.0, 5.0, 5.0), [ObstacleSpec(Circle((2.0, 0.0), 0.1),
                                                                Motion(((-2.0, 0.0),), 1.0))]).movers
    track = [[1.6, 0.0, 0.0, 0.0], [1.6, 0.0, 0.0, math.pi / 2]]
    margins = trajectory_margins([track[:1], track[1:]], [box.radius] * 2, NONE, movers, footprints=[box, box])
    assert margins.obstacles == pytest.approx([0.4 - 0.254 - 0.1, 0.4 - 0.215 - 0.1])


def test_the_barn_score_clips_the_traversal_time_between_two_and_eight_optimal_times() -> None:
    from fastep_core.metrics import barn_score

    assert barn_score(True, False, 7.0, 5.0) == 0.5                 # faster than 2 OT counts as 2 OT
    assert barn_score(True, False, 12.5, 5.0) == pytest.approx(0.4)
    assert barn_score(True, False, 100.0, 5.0) == pytest.approx(1 / 8)
    assert barn_score(True, True, 7.0, 5.0) == 0.0 == barn_score(False, False, None, 5.0)
    assert barn_score(True, False, 7.0, math.nan) == 0.0
