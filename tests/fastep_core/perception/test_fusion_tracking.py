"""Fusion with the map (fastep_core/perception/fusion.py) and the constant-velocity tracker (tracking.py)."""

from __future__ import annotations

import numpy as np
import pytest

from fastep_core.geometry import Circle, Obstacles, Segment
from fastep_core.perception.fusion import explained, seen_through
from fastep_core.perception.segmentation import scan_points
from fastep_core.perception.tracking import CONFIRM_HITS, MAX_COAST, Tracker
from fastep_core.sensing.laser import LaserSpec, scan

SPEC = LaserSpec(range=10.0, beams=360, noise=0.01)


def test_points_on_a_known_surface_are_explained_the_rest_are_not() -> None:
    pose = np.zeros(3)
    s = scan(SPEC, pose, np.random.default_rng(0), circles=[(5.0, 0.0), (0.0, 5.0)], radii=[1.0, 1.0],
             starts=[(-6.0, -3.0)], ends=[(6.0, -3.0)])
    points, _ = scan_points(s, pose)
    believed = Obstacles([Circle((5.0, 0.0), 1.0), Segment((-6.0, -3.0), (6.0, -3.0))])   # the map
    mask = explained(points, believed, np.zeros((0, 2)), np.zeros(0))
    unknown = np.abs(np.hypot(points[:, 0], points[:, 1] - 5.0) - 1.0) < 0.05
    assert unknown.any() and not mask[unknown].any() and mask[~unknown].all()
    # Another robot (odometry) explains the second circle's points.
    assert explained(points, believed, np.array([[0.0, 5.0]]), np.array([1.0])).all()


def test_a_misplaced_map_obstacle_is_seen_through_and_a_true_one_is_not() -> None:
    pose = np.zeros(3)
    s = scan(SPEC, pose, np.random.default_rng(0), circles=[(5.0, 0.0)], radii=[1.0], starts=[(-2.0, 4.0)],
             ends=[(2.0, 4.0)])
    believed = Obstacles([Circle((5.0, 0.0), 1.0), Circle((5.0, 2.5), 1.0),        # true, ghost (1.5 m off)
                          Segment((-2.0, 4.0), (2.0, 4.0)), Segment((-2.0, 3.0), (2.0, 3.0)),   # true, ghost
                          Circle((0.0, -12.0), 1.0)])                              # beyond the range: no evidence
    through = seen_through(s, pose, believed)   # in Obstacles' order: the circles, then the segments
    assert through.tolist() == [False, True, False, False, True]


def _outline(x0: float, x1: float, y: float, cell: float = 0.05) -> list[Segment]:
    """A /map's outline of a thin wall along y from x0 to x1 lying on a cell border: a cell on each side of it."""
    return [Segment((x0, y - cell), (x1, y - cell)), Segment((x0, y + cell), (x1, y + cell)),
            Segment((x0, y - cell), (x0, y + cell)), Segment((x1, y - cell), (x1, y + cell))]


def test_a_map_outline_a_cell_off_its_wall_is_not_seen_through_from_a_doorway() -> None:
    """A laser in a doorway of a thin wall (inside the band of the /map's outline a cell either side of it) reads
    far along the wall, past the outline's long sides: that says nothing of them, the wall lies within a cell."""
    pose = np.array([3.2, 7.02, 0.0])
    s = scan(SPEC, pose, np.random.default_rng(0), starts=[(3.6, 7.0), (3.2, 10.0)], ends=[(9.0, 7.0), (9.0, 10.0)])
    outline = _outline(3.6, 9.0, 7.0)
    through = seen_through(s, pose, Obstacles(outline))
    assert not through[:2].any()
    # Walls perception fitted itself get no band: those beams see through them.
    assert seen_through(s, pose, Obstacles(outline), map_walls=0)[:2].any()
    # The same outline 0.5 m off the true wall (misplaced) is seen through from there.
    assert seen_through(s, pose, Obstacles(_outline(3.6, 9.0, 6.5)))[1]


def test_a_beam_grazing_an_outline_round_the_true_corner_does_not_see_through_it() -> None:
    """A box the /map draws a cell too large: beams from the side pass just beyond the true corner, through the
    outline's extra cell, at a grazing angle. They cross its band beyond the wall's end: no evidence."""
    pose = np.array([3.05, 4.5, 0.0])
    box = [(4.35, 4.75), (4.85, 4.75), (4.85, 5.25), (4.35, 5.25)]
    fine = LaserSpec(10.0, 1.5 * np.pi, 720, 0.01)     # the robot harness's: a quarter degree between beams
    s = scan(fine, pose, np.random.default_rng(0), starts=box, ends=box[1:] + box[:1])
    drawn = Segment((4.35, 4.7), (4.85, 4.7))        # its near side, a cell off
    assert not seen_through(s, pose, Obstacles([drawn])).any()
    assert seen_through(s, pose, Obstacles([Segment((4.0, 3.0), (5.5, 3.0))])).all()   # where nothing is: a ghost


def test_an_obstacle_behind_another_is_not_seen_through() -> None:
    pose = np.zeros(3)
    s = scan(SPEC, pose, np.random.default_rng(0), circles=[(3.0, 0.0)], radii=[1.0])
    assert not seen_through(s, pose, Obstacles([Circle((7.0, 0.0), 0.8)])).any()


def run_tracker(seed: int, noise: float = 0.05, steps: int = 80, dt: float = 0.05) -> tuple[Tracker, np.ndarray]:
    """A mover at 0.6 m/s heading 30 degrees from (2, 1); detections with Gaussian noise, a still clutter
    detection that appears now and then."""
    rng = np.random.default_rng(seed)
    velocity = 0.6 * np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    tracker = Tracker()
    for k in range(steps):
        t = k * dt
        truth = np.array([2.0, 1.0]) + velocity * t
        centres = [truth + rng.normal(0.0, noise, 2)]
        if k % 7 == 0:
            centres.append(np.array([-3.0, 4.0]) + rng.normal(0.0, noise, 2))
        tracker.update(t, np.array(centres), np.full(len(centres), 0.5))
    return tracker, velocity


def test_the_tracker_converges_to_the_movers_velocity_through_noise() -> None:
    tracker, velocity = run_tracker(0)
    mover = np.flatnonzero(tracker.confirmed & (tracker.hits > 50))
    assert len(mover) == 1
    state = tracker.states[mover[0]]
    np.testing.assert_allclose(state[2:], velocity, atol=0.1)
    np.testing.assert_allclose(state[:2], np.array([2.0, 1.0]) + velocity * 79 * 0.05, atol=0.1)


def test_the_tracker_is_deterministic() -> None:
    a, _ = run_tracker(3)
    b, _ = run_tracker(3)
    np.testing.assert_array_equal(a.states, b.states)
    np.testing.assert_array_equal(a.ids, b.ids)


@pytest.mark.parametrize('hits', [1, CONFIRM_HITS])
def test_tracks_are_confirmed_after_enough_hits_and_deleted_after_coasting(hits: int) -> None:
    tracker = Tracker()
    for k in range(hits):
        tracker.update(0.05 * k, np.array([[1.0, 1.0]]), np.array([0.3]))
    assert tracker.confirmed.tolist() == [hits >= CONFIRM_HITS]
    tracker.update(0.05 * hits + MAX_COAST - 0.1, np.zeros((0, 2)), np.zeros(0))
    assert len(tracker) == 1                      # coasting
    tracker.update(0.05 * hits + MAX_COAST + 0.1, np.zeros((0, 2)), np.zeros(0))
    assert len(tracker) == 0                      # deleted


def test_two_movers_crossing_keep_their_tracks() -> None:
    """Gating + the Hungarian pairing: two movers passing 1 m apart keep their identities."""
    tracker = Tracker()
    for k in range(60):
        t = 0.05 * k
        a = np.array([0.0 + 0.8 * t, 0.5])
        b = np.array([2.4 - 0.8 * t, -0.5])
        tracker.update(t, np.array([a, b]), np.array([0.4, 0.4]))
    assert len(tracker) == 2 and tracker.ids.tolist() == [0, 1]
    np.testing.assert_allclose(tracker.states[:, 2], [0.8, -0.8], atol=0.05)


def test_a_ghost_a_little_off_does_not_hide_the_true_surface() -> None:
    """A map circle misplaced by 0.2 m away from the robot: the true surface's points facing the robot are not
    that ghost (with a 0.25 m tolerance they were, and robots grazed the truth: docs/dynamic_world.md)."""
    pose = np.zeros(3)
    s = scan(SPEC, pose, np.random.default_rng(0), circles=[(4.0, 0.0)], radii=[1.0])
    points, _ = scan_points(s, pose)
    ghost = Obstacles([Circle((4.2, 0.0), 1.0)])
    facing = np.abs(points[:, 1]) < 0.3          # the part of the surface nearest the robot
    assert facing.any() and not explained(points[facing], ghost, np.zeros((0, 2)), np.zeros(0)).any()
