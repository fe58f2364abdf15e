"""A still world stays still: no phantom movers, surfaces believed no farther than the beams show them, things
seen are obstacles at once and kept until beams show their place free (issue "A laser it can trust", item 3)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.experiments.batches import cached_scenario
from fastep_core.geometry import Circle, Obstacles, Segment
from fastep_core.perception.belief import IN_FRONT, Perception
from fastep_core.perception.fusion import seen_through
from fastep_core.perception.segmentation import scan_points, segment
from fastep_core.perception.shapes import shapes
from fastep_core.planning.recovery.back_up import SeenFree
from fastep_core.sensing.laser import LaserSpec, Scan, fan_hits, scan
from fastep_core.simulator import Tick, simulate
from fastep_core.world import World

SPEC = LaserSpec(range=10.0, fov=1.5 * math.pi, beams=720, noise=0.01)
EMPTY = World((-20.0, -20.0, 20.0, 20.0), ())


def sweep(truth_circles: list[tuple[float, float, float]], poses: list[tuple[float, float, float]],
          map_world: World = EMPTY, seed: int = 0) -> Perception:
    """A Perception fed one scan of the still circles (x, y, r) from each pose, 0.05 s apart."""
    rng = np.random.default_rng(seed)
    perception = Perception(SPEC, map_world)
    centres = np.array([c[:2] for c in truth_circles], dtype=float).reshape(-1, 2)
    radii = np.array([c[2] for c in truth_circles], dtype=float)
    for k, pose in enumerate(poses):
        reading = scan(SPEC, pose, rng, k * 0.05, centres, radii)
        perception.update(k * 0.05, pose, reading)
    return perception


def test_a_dense_laser_only_clutter_world_shows_no_mover_and_is_crossed_without_touching() -> None:
    """dense_clutter_laser:1000000 (static, obstacles only in the laser): the robot driving through it at up to 2 m/s
    once tracked 15 'movers' (up to 11 at once), fitted circles whose centres wandered with the viewpoint."""
    ticks: list[Tick] = []
    run = simulate(cached_scenario('dense_clutter_laser:1000000'), 'fastep_route', 0, observer=ticks.append)
    assert run.robots[0].reached and not run.robots[0].collided
    assert not any(t.belief.movers for t in ticks if t.belief is not None)


def test_a_thing_seen_is_an_obstacle_from_its_third_scan_and_not_a_mover() -> None:
    poses = [(0.0, 0.05 * k, 0.0) for k in range(4)]
    perception = sweep([(3.0, 0.0, 0.3)], poses[:2])
    assert not perception.world.obstacle_list                      # a tentative track: nothing yet
    perception = sweep([(3.0, 0.0, 0.3)], poses)
    circles = [o for o in perception.world.obstacle_list if isinstance(o, Circle)]
    assert len(circles) == 1 and math.dist(circles[0].center, (3.0, 0.0)) < 0.05
    assert not perception.belief.movers


def test_a_standing_thing_unseen_stays_where_it_was_last_seen() -> None:
    """Behind the robot (outside a 270-degree laser's view) it is no longer seen: it is kept, where it was."""
    forward = [(0.0, 0.0, 0.0)] * 6
    backward = [(0.0, 0.0, math.pi)] * 40                 # 2 s facing away: longer than a track coasts unseen
    perception = sweep([(3.0, 0.0, 0.3)], forward + backward)
    circles = [o for o in perception.world.obstacle_list if isinstance(o, Circle)]
    assert len(circles) == 1 and math.dist(circles[0].center, (3.0, 0.0)) < 0.05


def test_nan_readings_see_through_nothing_and_inf_sees_through() -> None:
    wall = Obstacles([Segment((2.0, -1.0), (2.0, 1.0))])
    angles = np.linspace(-0.3, 0.3, 31)
    base = dict(angle_min=float(angles[0]), angle_max=float(angles[-1]), angle_increment=float(angles[1] - angles[0]),
                range_min=0.05, range_max=10.0)
    pose = np.zeros(3)
    assert not seen_through(Scan(**base, ranges=np.full(31, np.nan)), pose, wall).any()
    assert seen_through(Scan(**base, ranges=np.full(31, np.inf)), pose, wall).all()


def test_a_disc_its_own_scan_sees_through_is_no_circle() -> None:
    """Two poles with a 0.1 m gap between them fit one disc over the gap; beams through it say it is not one."""
    reading = scan(SPEC, (0.0, 0.0, 0.0), np.random.default_rng(0), 0.0, np.array([[3.0, -0.15], [3.0, 0.15]]),
                   np.array([0.1, 0.1]))
    points, beams = scan_points(reading, np.zeros(3))
    labels = np.zeros(len(points), dtype=np.int64)           # taken as one cluster
    plain = shapes(points, beams, labels, np.zeros(2), SPEC.noise)

    def seen_free(centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
        circles = Obstacles([Circle((float(c[0]), float(c[1])), float(r)) for c, r in zip(centres, radii)])
        return seen_through(reading, np.zeros(3), circles, 0.03)
    checked = shapes(points, beams, labels, np.zeros(2), SPEC.noise, seen_free=seen_free)
    assert len(plain.radii) == 1 and len(checked.radii) == 0


def test_a_wall_is_believed_at_its_nearest_return() -> None:
    """A bumpy wall (poles side by side) simplified within the tolerance: no return lies in front of its pieces."""
    centres = np.column_stack([np.full(13, 3.0), np.linspace(-0.9, 0.9, 13)])
    reading = scan(SPEC, (0.0, 0.0, 0.0), np.random.default_rng(1), 0.0, centres, np.full(13, 0.075))
    points, beams = scan_points(reading, np.zeros(3))
    labels = segment(reading, points, beams, SPEC.noise, SPEC.full_turn)
    found = shapes(points, beams, labels, np.zeros(2), SPEC.noise)
    assert len(found.starts) and not len(found.radii)
    walls = Obstacles([Segment(tuple(a), tuple(b)) for a, b in zip(found.starts, found.ends)])
    beam, _, expected = fan_hits(np.zeros(2), 0.0, reading.angle_min, reading.angle_increment, len(reading.ranges),
                                 starts=walls.starts, ends=walls.ends)
    nearest = np.full(len(reading.ranges), np.inf)
    np.minimum.at(nearest, beam, expected)
    hit = np.isfinite(nearest) & np.isfinite(reading.ranges)
    assert hit.sum() > 50
    assert (reading.ranges[hit] >= nearest[hit] - 1e-9).all()


def test_a_surface_in_front_of_what_is_believed_is_marked() -> None:
    """The map has a pole 0.1 m behind where it is (within EXPLAINED of it, so its returns once counted as the
    map's): the returns in front of the map's surface make the belief reach the true one."""
    truth = (3.0, 0.0, 0.3)
    mapped = World(EMPTY.workspace, (Circle((3.1, 0.0), 0.3),))
    perception = sweep([truth], [(0.0, 0.0, 0.0)] * 6, mapped)
    believed = perception.world.obstacles
    surface = np.array([[2.7, 0.0]])                           # the true surface facing the robot
    assert float(believed.clearance(surface)[0]) <= IN_FRONT


def test_free_space_with_a_margin_leaves_out_a_grazing_beam_s_edge() -> None:
    reading = scan(SPEC, (0.0, 0.0, 0.0), np.random.default_rng(0), 0.0, np.array([[3.0, 0.0]]), np.array([0.3]))
    free = SeenFree.of_scans([(reading, (0.0, 0.0, 0.0))])
    beside = np.array([[3.0, 0.34]])                          # 4 cm beside the pole, beyond its near side
    assert free.covers(beside)[0] and not free.covers(beside, 0.1)[0]
    assert free.covers(np.array([[1.5, 0.0]]), 0.1)[0]        # well inside the free fan


@pytest.mark.parametrize('mount', [(0.0, 0.0, 0.0), (0.25, 0.0, 0.0)])
def test_a_turning_robot_in_a_still_room_tracks_no_mover(mount: tuple[float, float, float]) -> None:
    """Scans of a still room of poles from a robot turning in place (the scanner off its centre or on it)."""
    spec = LaserSpec(10.0, 1.5 * math.pi, 720, 0.01, mount)
    poles = np.array([[2.0, 1.0], [2.5, -1.2], [-1.5, 2.0], [3.0, 0.2], [-2.0, -2.0]])
    perception = Perception(spec, EMPTY)
    rng = np.random.default_rng(3)
    for k in range(60):
        pose = spec.pose_on((0.0, 0.0, 0.1 * k))
        reading = scan(spec, pose, rng, 0.05 * k, poles, np.full(len(poles), 0.1))
        belief = perception.update(0.05 * k, pose, reading)
        assert not belief.movers
