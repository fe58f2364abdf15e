"""A robot with a footprint in planning (planning/outline.py): planned with the circle its box fits heading along
its way, guarded by the placed polygon along the predicted motion, its backing up checked with the outline."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from fastep_core.errors import ParameterError
from fastep_core.footprint import Footprint
from fastep_core.geometry import Circle, Segment
from fastep_core.kinematics.diff_drive import DiffDrive
from fastep_core.planning import OtherRobot, PlannerParams, make_navigator
from fastep_core.planning.control import ControlTick
from fastep_core.planning.outline import FOOTPRINT_MARGIN, inflated, planning_radius, predicted_poses
from fastep_core.planning.recovery.back_up import reverse_free
from fastep_core.planning.safety.guard import Guard, ScanReturns, Stop
from fastep_core.scenario import RobotSpec, parse_scenario
from fastep_core.simulator import simulate
from fastep_core.world import World

JACKAL = [[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]]
BOX = Footprint.parse(JACKAL)
MODEL = DiffDrive(2.0, 2.0)
AT = np.array([5.0, 5.0, 0.0])
# A wall along the robot's left side, 6 cm off the box's side (0.275 m from base_link): inside the 0.333 m circle
# a corner sweeps when the box turns in place, outside the box heading along it.
BESIDE = World.from_obstacles([0, 0, 10, 10], [Segment((4.0, 5.275), (6.0, 5.275))])


def test_a_footprint_robot_plans_with_its_inscribed_circle_and_knows_its_outline() -> None:
    spec = RobotSpec('r1', 'diff_drive', (1.0, 1.0, 0.0), (9.0, 1.0), BOX.radius, footprint=BOX)
    nav = make_navigator('fastep_route', spec, BOX.radius, BESIDE, PlannerParams(), 0)
    assert nav.footprint == BOX and nav.guard_check.footprint == BOX
    assert nav.radius == planning_radius(BOX, BOX.radius) == BOX.inscribed + FOOTPRINT_MARGIN
    assert abs(BOX.inscribed - 0.215) < 1e-12
    # Other robots are kept from the circumscribed circle: they are grown by the difference.
    (grown,) = inflated([OtherRobot('r2', (3.0, 3.0), radius=0.3)], nav.outline_extra)
    assert abs(grown.radius + nav.radius - (0.3 + BOX.radius)) < 1e-12
    assert ControlTick(nav).guard.footprint == BOX
    circle = make_navigator('fastep_route', RobotSpec('r1', 'diff_drive', (1.0, 1.0, 0.0), (9.0, 1.0), 0.3), 0.3,
                            BESIDE, PlannerParams(), 0)
    assert circle.footprint is None and circle.radius == 0.3 and circle.outline_extra == 0.0


def test_the_guard_refuses_a_turn_in_place_that_swings_a_corner_into_a_wall_beside_the_robot() -> None:
    turn = np.array([0.0, 1.0])   # 0.5 rad over the 0.5 s checked: the front-left corner reaches 0.31 m across
    boxed = Guard(MODEL, planning_radius(BOX, BOX.radius), PlannerParams(), BOX)
    assert np.all(boxed.check(BESIDE, AT, turn, 0.5, []) == 0.0) and boxed.stop is Stop.OBSTACLE
    assert 'outline' in boxed.reason
    # A circle of the inscribed radius turns in place without moving at all.
    inscribed = Guard(MODEL, BOX.inscribed, PlannerParams())
    assert inscribed.check(BESIDE, AT, turn, 0.5, []) is turn
    # Turning the other way swings the rear corner at it instead; driving along the wall is let through.
    assert np.all(boxed.check(BESIDE, AT, -turn, 0.5, []) == 0.0)
    along = np.array([1.0, 0.0])
    assert boxed.check(BESIDE, AT, along, 0.5, []) is along


def test_the_guard_checks_the_whole_sweep_not_only_where_the_turn_ends() -> None:
    """A half turn ends with the box where it started (a rectangle about its centre); its corners swept the
    circumscribed circle on the way, and the wall 6 cm off the side is inside it."""
    half, quick = np.array([0.0, np.pi]), DiffDrive(2.0, 4.0)
    poses = predicted_poses(quick, AT, half, 1.0, BOX.radius)
    assert len(poses) > 10 and np.allclose(poses[0], AT) and abs(poses[-1, 2] - np.pi) < 1e-12
    assert abs(float(BOX.clearance(poses[-1], BESIDE.obstacles)) - 0.06) < 1e-9
    guard = Guard(quick, 0.235, PlannerParams(), BOX)
    assert np.all(guard.check(BESIDE, AT, half, 1.0, []) == 0.0)


def test_the_guard_refuses_a_turn_that_swings_a_corner_into_laser_returns() -> None:
    """Returns along the same line as the wall, the belief empty: the beams' ends stop the turn as well."""
    empty = World.from_obstacles([0, 0, 10, 10], [])
    guard = Guard(MODEL, 0.235, PlannerParams(), BOX)
    points = np.column_stack([np.linspace(4.5, 5.5, 41), np.full(41, 5.275)])
    guard.scan_points = ScanReturns(points, AT[:2], 0.235)
    turn = np.array([0.0, 1.0])
    assert np.all(guard.check(empty, AT, turn, 0.5, []) == 0.0) and 'laser' in guard.reason
    along = np.array([0.5, 0.0])
    assert guard.check(empty, AT, along, 0.5, []) is along


def test_backing_up_checks_the_box_rear_not_only_the_planning_circle() -> None:
    """A post 0.30 m behind base_link: backing 5 cm keeps the 0.235 m circle clear and brings the box's rear
    (0.254 m behind) onto it."""
    post = World.from_obstacles([0, 0, 10, 10], [Circle((4.68, 5.0), 0.02)])
    back = np.array([-0.25, 0.0])
    assert reverse_free(MODEL, AT, 0.235, back, 0.2, post)
    assert not reverse_free(MODEL, AT, 0.235, back, 0.2, post, footprint=BOX)
    assert reverse_free(MODEL, AT, 0.235, np.array([0.25, 0.0]), 0.2, post, footprint=BOX)


def _gap_world(**robot: Any) -> dict[str, Any]:
    # A wall across the way with a 0.56 m gap: the box (0.43 m wide) fits through heading along the way, its
    # circumscribed circle (0.666 m across) does not.
    spec = {'name': 'r1', 'model': 'diff_drive', 'start': [1.0, 3.0, 0.0], 'goal': [5.0, 3.0], **robot}
    return {'name': 'gap', 'workspace': [0, 0, 6, 6],
            'obstacles': [{'segment': {'start': [3.0, 0.0], 'end': [3.0, 2.72]}},
                          {'segment': {'start': [3.0, 3.28], 'end': [3.0, 6.0]}}],
            'planner': {'max_speed': 1.0, 'max_sim_time': 60.0},
            'robots': [spec]}


def test_a_box_robot_passes_a_gap_its_circumscribed_circle_does_not_fit() -> None:
    boxed = simulate(parse_scenario(_gap_world(footprint=JACKAL)), 'fastep_route', 0).robots[0]
    assert boxed.reached and not boxed.collided and boxed.min_clearance > 0.0
    # The same robot as its circumscribed circle finds no way through.
    circled = simulate(parse_scenario(_gap_world(radius=BOX.radius)), 'fastep_route', 0).robots[0]
    assert not circled.reached


def test_the_returns_near_where_the_scan_was_taken_give_the_outline_every_decision_all_of_them_give() -> None:
    """ScanReturns.around_outline: while the robot is near where it took the scan, only the returns within the
    circumscribed radius and NEAR_ROOM of there are measured; the guard decides as with every return."""
    rng = np.random.default_rng(4)
    points = AT[:2] + rng.uniform(-3.0, 3.0, (720, 2))
    points = points[np.hypot(*(points - AT[:2]).T) > 0.30]   # none inside the box where it stands
    empty = World.from_obstacles([0, 0, 10, 10], [])
    near, every = Guard(MODEL, 0.235, PlannerParams(), BOX), Guard(MODEL, 0.235, PlannerParams(), BOX)
    near.scan_points = ScanReturns(points, AT[:2], 0.235)
    every.scan_points = ScanReturns(points, AT[:2] + 100.0, 0.235)   # taken far off: every return is measured
    assert len(near.scan_points.around_outline(AT[None, :2], BOX.radius)) < len(points) // 4
    decisions = []
    for v, omega in rng.uniform([-0.5, -2.0], [2.0, 2.0], (40, 2)):
        command = np.array([v, omega])
        decisions.append(near.check(empty, AT, command, 0.2, []) is command)
        assert decisions[-1] == (every.check(empty, AT, command, 0.2, []) is command)
    assert any(decisions) and not all(decisions)


def test_a_footprint_is_for_a_diff_drive_robot_only() -> None:
    spec = RobotSpec('r1', 'point_mass', (1.0, 1.0), (9.0, 1.0), 0.5)
    with pytest.raises(ParameterError, match='diff_drive robots only'):
        make_navigator('fastep', spec, 0.5, BESIDE, PlannerParams(), 0, footprint=BOX)
