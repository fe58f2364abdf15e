"""Clustering of known layouts (fastep_core/perception/segmentation.py) and the shapes fitted to them (shapes.py)."""

from __future__ import annotations

import numpy as np
import pytest

from fastep_core.perception.segmentation import scan_points, segment
from fastep_core.perception.shapes import fit_circles, polyline, shapes
from fastep_core.sensing.laser import LaserSpec, scan

SPEC = LaserSpec(range=10.0, beams=360, noise=0.01)


def layout(pose: tuple[float, float, float] = (0.0, 0.0, 0.0), seed: int = 0, **world: object) -> tuple:
    s = scan(SPEC, pose, np.random.default_rng(seed), **world)  # type: ignore[arg-type]  # test keywords
    points, beams = scan_points(s, np.array(pose))
    return s, points, beams, segment(s, points, beams, SPEC.noise, SPEC.full_turn)


def test_points_are_where_the_beams_hit() -> None:
    s, points, beams, _ = layout((1.0, 2.0, 0.7), circles=[(6.0, 2.0)], radii=[1.0])
    # Every point lies on the circle (within the noise) and comes from a finite beam.
    assert len(points) > 10 and np.isfinite(s.ranges[beams]).all()
    np.testing.assert_allclose(np.hypot(points[:, 0] - 6.0, points[:, 1] - 2.0), 1.0, atol=0.05)


def test_three_circles_and_a_wall_are_four_clusters() -> None:
    _, points, beams, labels = layout(circles=[(5.0, 0.0), (0.0, 6.0), (-4.0, -4.0)], radii=[1.0, 0.5, 1.5],
                                      starts=[(3.0, -6.0)], ends=[(8.0, -3.0)])
    assert labels.max() + 1 == 4
    # Each circle's points make exactly one cluster.
    for centre, radius in (((5.0, 0.0), 1.0), ((0.0, 6.0), 0.5), ((-4.0, -4.0), 1.5)):
        on = np.abs(np.hypot(points[:, 0] - centre[0], points[:, 1] - centre[1]) - radius) < 0.05
        assert len(set(labels[on])) == 1


def test_two_circles_side_by_side_with_a_gap_are_two_clusters() -> None:
    _, _, _, labels = layout(circles=[(6.0, -1.3), (6.0, 1.3)], radii=[1.0, 1.0])
    assert labels.max() + 1 == 2


def test_a_cluster_across_the_turn_boundary_is_one() -> None:
    # A circle straight behind a point mass: its beams are the last and the first ones of the full turn.
    _, points, beams, labels = layout(circles=[(-5.0, 0.0)], radii=[1.0])
    assert beams[0] == 0 and beams[-1] == SPEC.beams - 1
    assert labels.max() == 0


@pytest.mark.parametrize('pose', [(0.0, 0.0, 0.0), (30.0, 40.0, 1.0)])
def test_circles_are_fitted_where_they_are(pose: tuple[float, float, float]) -> None:
    x, y = pose[0], pose[1]
    truth = [(x + 5.0, y), (x, y + 6.0), (x - 4.0, y - 4.0)]
    radii = [1.0, 0.5, 1.5]
    s, points, beams, labels = layout(pose, circles=truth, radii=radii)
    found = shapes(points, beams, labels, np.array(pose[:2]), SPEC.noise)
    assert len(found.radii) == 3 and len(found.starts) == 0
    order = np.argsort(found.radii)
    np.testing.assert_allclose(found.radii[order], sorted(radii), atol=0.05)
    np.testing.assert_allclose(found.centres[order], np.array(truth)[np.argsort(radii)], atol=0.05)


def test_a_wall_is_a_segment_and_a_corner_two() -> None:
    _, points, beams, labels = layout(starts=[(4.0, -3.0)], ends=[(4.0, 3.0)])
    found = shapes(points, beams, labels, np.zeros(2), SPEC.noise)
    assert len(found.radii) == 0 and len(found.starts) == 1
    np.testing.assert_allclose(found.starts[0][0], 4.0, atol=0.05)
    np.testing.assert_allclose(sorted([found.starts[0][1], found.ends[0][1]]), [-3.0, 3.0], atol=0.15)
    _, points, beams, labels = layout(starts=[(4.0, -3.0), (4.0, 3.0)], ends=[(4.0, 3.0), (-2.0, 3.0)])
    found = shapes(points, beams, labels, np.zeros(2), SPEC.noise)
    assert len(found.radii) == 0 and len(found.starts) == 2


def test_a_far_partial_arc_is_neither_circle_nor_wall_yet() -> None:
    """A big circle entering the range shows a few points: no circle fits them reliably, and beyond wall_range
    they wait (seen better later), rather than becoming a wall."""
    s = scan(LaserSpec(range=8.0, beams=360, noise=0.01), (0.0, 0.0, 0.0), np.random.default_rng(0),
             circles=[(9.4, 0.0)], radii=[1.5])
    points, beams = scan_points(s, np.zeros(3))
    labels = segment(s, points, beams, 0.01)
    assert 3 <= len(points) < 12
    found = shapes(points, beams, labels, np.zeros(2), 0.01, wall_range=0.6 * 8.0)
    assert len(found.radii) == 0 and len(found.starts) == 0


def test_kasa_fit_is_exact_on_exact_points() -> None:
    angles = np.linspace(0.0, 1.5, 9)
    points = np.column_stack([3.0 + 2.0 * np.cos(angles), -1.0 + 2.0 * np.sin(angles)])
    centres, radii, rms = fit_circles(points, np.zeros(9, dtype=np.int64), 1)
    np.testing.assert_allclose(centres[0], [3.0, -1.0], atol=1e-9)
    np.testing.assert_allclose(radii[0], 2.0, atol=1e-9)
    assert rms[0] < 1e-9


def test_douglas_peucker_keeps_the_corner() -> None:
    points = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [2.0, 2.0]])
    assert polyline(points) == [0, 2, 4]
