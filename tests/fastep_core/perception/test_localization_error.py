"""Perception that tolerates localization error (issue 43, item 3): a surface the laser sees within the pose's
uncertainty of a mapped one is that one, not a new obstacle; a drifting estimate does not close the way; what is
really new beyond the uncertainty is still seen."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from fastep_core.geometry import Circle, Obstacle, Obstacles, Segment
from fastep_core.perception.belief import Belief, BelievedWorld, Perception
from fastep_core.perception.fusion import END_SLACK, EXPLAINED, explained_within
from fastep_core.perception.uncertainty import MAX_SLACK, OdometryDrift, PoseError, PoseUncertainty
from fastep_core.planning.algorithms import make_navigator
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.scenario import RobotSpec, parse_scenario
from fastep_core.sensing.laser import LaserSpec, scan
from fastep_core.simulator import simulate
from fastep_core.world import World

SPEC = LaserSpec(range=10.0, fov=1.5 * math.pi, beams=720, noise=0.01)
DOOR = 0.6                    # m: a doorway in a wall across the way, 0.16 m wider than the robot
LEFT, RIGHT = 10.0 - DOOR / 2, 10.0 + DOOR / 2
WALLS = [Segment((0.0, 5.0), (LEFT, 5.0)), Segment((RIGHT, 5.0), (20.0, 5.0)),
         Segment((LEFT, 5.0), (LEFT, 5.3)), Segment((RIGHT, 5.0), (RIGHT, 5.3))]
MAP = World((0.0, 0.0, 20.0, 10.0), tuple(WALLS))
OFFSET = (0.03, -0.02, math.radians(1.0))      # a localizer 3.6 cm and a degree off ...
DRIFT = OdometryDrift(0.002, math.radians(0.02))   # ... and odometry drifting 0.2 % and 0.02 degree per metre
TOLD = PoseUncertainty(0.04, math.radians(1.2))


def approach(uncertainty: PoseUncertainty | None, extra: list[Segment] | None = None) -> Belief:
    """Perception of 60 scans of the doorway's truth (and `extra` walls the map lacks) from a robot driving 3 m
    toward it, each placed at a pose off the truth by OFFSET and DRIFT's drift."""
    truth_walls = WALLS + (extra or [])
    starts = np.array([w.start for w in truth_walls])
    ends = np.array([w.end for w in truth_walls])
    rng = np.random.default_rng(0)
    perception = Perception(SPEC, MAP)
    belief = perception.belief
    for k in range(60):
        driven = 0.05 * k
        truth = (10.0, 1.0 + driven, math.pi / 2)
        placed = (truth[0] + OFFSET[0] + DRIFT.translation * driven, truth[1] + OFFSET[1],
                  truth[2] + OFFSET[2] + DRIFT.yaw * driven)
        reading = scan(SPEC, truth, rng, 0.05 * k, starts=starts, ends=ends)
        told = None if uncertainty is None else uncertainty + DRIFT.bound(driven)
        belief = perception.update(0.05 * k, placed, reading, uncertainty=told)
    return belief


def test_walls_seen_from_a_pose_off_the_truth_are_the_mapped_walls() -> None:
    """Told nothing, the doorway's walls placed 2-10 cm off became walls of their own beside the map's (up to
    0.25 m off its line at the far end), and a map wall was seen through and dropped; told the uncertainty, the
    belief is the map."""
    before = approach(None)
    assert before.dropped and len(before.seen_obstacles) >= 3
    after = approach(TOLD)
    assert not after.seen_obstacles and not after.dropped
    assert after.world.obstacle_list == MAP.obstacle_list
    assert shortest_path(after.world, np.array([10.0, 4.0]), np.array([10.0, 9.0]), 0.22) is not None


def test_a_wall_beyond_the_uncertainty_is_still_new() -> None:
    """A wall 0.4 m in front of the mapped one (more than any return's slack here) is seen, where the pose that is
    off puts it (up to 0.16 m from the truth, 6 m away at a degree and more)."""
    unknown = Segment((4.0, 4.6), (8.0, 4.6))
    after = approach(TOLD, [unknown])
    seen = [o for o in after.seen_obstacles if isinstance(o, Segment)]
    assert seen and all(abs(o.start[1] - 4.6) < 0.2 and abs(o.end[1] - 4.6) < 0.2 for o in seen)
    assert not after.dropped


def door_world(model: str) -> dict[str, Any]:
    start = [10.0, 1.0, math.pi / 2] if model == 'diff_drive' else [10.0, 1.0]
    return {'workspace': [0, 0, 20, 10],
            'obstacles': [{'segment': {'start': list(w.start), 'end': list(w.end)}} for w in WALLS],
            'robots': [{'name': 'r1', 'model': model, 'start': start, 'goal': [10.0, 9.0], 'radius': 0.22,
                        'sensor': {'range': 10.0, 'fov': round(1.5 * math.pi, 9), 'beams': 720, 'noise': 0.01}}]}


@pytest.mark.parametrize('model, yaw, failure', [('point_mass', 2.0, 'no valid path'),
                                                 ('diff_drive', 1.0, 'failed to make progress')])
def test_a_robot_localized_off_the_truth_goes_through_the_doorway(model: str, yaw: float, failure: str) -> None:
    """fastep-sim with a localization error (simulator pose_error): told nothing, perception closed the doorway
    (the point mass 2 degrees off: 'no valid path'; the differential drive a degree off held until it made no
    progress); told the uncertainty, both go through without touching."""
    scenario = parse_scenario(door_world(model))
    error = PoseError((OFFSET[0], OFFSET[1], math.radians(yaw)), DRIFT, 0)
    blind = simulate(scenario, 'fastep_route', 0, pose_error=error).robots[0]
    assert not blind.reached and failure in blind.status
    if failure == 'no valid path':   # what closed the doorway: a wall seen beside the map's, where it lies
        assert 'in the way: a wall from' in blind.status and 'seen by the laser, its ends up to' in blind.status
    told = PoseError((OFFSET[0], OFFSET[1], math.radians(yaw)), DRIFT, 0,
                     told=PoseUncertainty(0.04, math.radians(1.2 * yaw)), told_drift=DRIFT)
    robot = simulate(scenario, 'fastep_route', 0, pose_error=told).robots[0]
    assert robot.reached and not robot.collided, robot.status
    assert robot.belief is not None and not robot.belief.seen_obstacles and not robot.belief.dropped


def test_pose_uncertainty_from_a_covariance_and_a_drift() -> None:
    covariance = np.zeros((6, 6))
    covariance[0, 0], covariance[1, 1], covariance[0, 1] = 4e-4, 1e-4, 0.0
    covariance[5, 5] = 3e-4
    bound = PoseUncertainty.from_covariance(covariance.ravel())
    assert bound.translation == pytest.approx(3.0 * 0.02) and bound.yaw == pytest.approx(3.0 * math.sqrt(3e-4))
    small = PoseUncertainty.from_covariance(np.diag([4e-4, 4e-4, 1e-4]), sigmas=2.0)
    assert small.translation == pytest.approx(0.04) and small.yaw == pytest.approx(0.02)
    with pytest.raises(ValueError):
        PoseUncertainty.from_covariance(np.full(36, np.nan))
    with pytest.raises(ValueError):
        PoseUncertainty(-0.01, 0.0)
    drift = OdometryDrift(0.01, 0.002).bound(10.0)
    assert drift.translation == pytest.approx(0.1 + 0.1) and drift.yaw == pytest.approx(0.02)
    slack = PoseUncertainty(0.05, 0.01).slack(np.array([0.0, 5.0, 1e3]))
    np.testing.assert_allclose(slack, [0.05, 0.1, MAX_SLACK])


def test_the_simulated_error_grows_as_its_bound_says() -> None:
    """PoseError on a straight 20 m run: the estimate within the bound it would be told, the heading's drift
    turning the way driven (as integrated odometry does)."""
    error = PoseError((0.03, -0.02, 0.01), OdometryDrift(0.002, 0.001), 3)
    for x in np.linspace(0.0, 20.0, 401):
        estimate = error.estimate(np.array([x, 0.0, 0.0]))
    bound = PoseUncertainty(math.hypot(0.03, 0.02), 0.01) + OdometryDrift(0.002, 0.001).bound(error.distance)
    assert error.distance == pytest.approx(20.0)
    assert math.hypot(estimate[0] - 20.0, estimate[1]) <= bound.translation + 1e-9
    assert abs(estimate[2]) <= bound.yaw + 1e-12
    assert abs(estimate[1]) > 0.1     # 0.2 m across, from the heading's drift alone


def random_world(rng: np.random.Generator, circles: int, segments: int) -> list[Obstacle]:
    """Circles and segments about the origin, a few segments of zero length."""
    items: list[Obstacle] = [Circle((float(x), float(y)), float(r)) for (x, y), r in
                             zip(rng.uniform(-9.0, 9.0, (circles, 2)), rng.uniform(0.05, 1.5, circles))]
    for a, run in zip(rng.uniform(-9.0, 9.0, (segments, 2)), rng.normal(0.0, 2.0, (segments, 2))):
        b = a if rng.random() < 0.1 else a + run
        items.append(Segment((float(a[0]), float(a[1])), (float(b[0]), float(b[1]))))
    return items


@pytest.mark.parametrize('seed', range(10))
def test_explained_within_is_each_point_against_each_obstacle(seed: int) -> None:
    """The vectorised test against Obstacles.near, one point at a time at its own tolerance."""
    rng = np.random.default_rng(seed)
    obstacles = Obstacles(random_world(rng, 6, 8))
    points = rng.uniform(-10.0, 10.0, (300, 2))
    within = EXPLAINED + rng.uniform(0.0, 0.4, 300)
    slack = END_SLACK + rng.uniform(0.0, 0.4, 300)
    expected = [bool(obstacles.near(p[None], float(w), float(e))[0]) for p, w, e in zip(points, within, slack)]
    assert explained_within(points, obstacles, within, slack).tolist() == expected


def test_a_failure_says_what_was_seen_and_how_far_from_the_map() -> None:
    """Where a belief truly blocks, the goal's failure (and the hold before it) names the obstacle in the way, its
    place and size, and for one the laser showed how far it lies from the map's nearest obstacle."""
    room = [Segment((10.0, 0.0), (10.0, 9.0)), Segment((10.0, 11.0), (10.0, 20.0))]
    seen = Segment((10.1, 8.0), (10.1, 12.0))                 # seen 0.1 m beside the mapped wall, across its door
    world = BelievedWorld((0.0, 0.0, 20.0, 20.0), (*room, seen), (seen,), tuple(room))
    nav = make_navigator('fastep_route', RobotSpec('r1', 'point_mass', (5.0, 10.0), (15.0, 10.0), 0.5), 0.5, world,
                         PlannerParams(blocked_timeout=0.5), 0)
    nav.from_scans = True
    nav.set_goal((15.0, 10.0))
    nav.update(0.0, np.array([5.0, 10.0]))
    assert 'in the way: a wall from (10.10, 8.00) to (10.10, 12.00), seen by the laser, its ends up to 0.10 m from ' \
        'the nearest obstacle of the map' in nav.reason and nav.reason.startswith('blocked'), nav.reason
    for k in range(1, 20):
        nav.update(0.05 * k, np.array([5.0, 10.0]))
    assert nav.failed and nav.reason.startswith('no valid path') and 'seen by the laser, its ends up to 0.10 m' in \
        nav.reason, nav.reason
