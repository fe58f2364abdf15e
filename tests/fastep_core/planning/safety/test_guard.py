"""The guard (planning/safety/guard.py) and the navigator's detection, with the world changing under them."""

from __future__ import annotations

import numpy as np

from fastep_core.geometry import Circle
from fastep_core.kinematics import PointMass
from fastep_core.planning import OtherRobot, PlannerParams, make_navigator
from fastep_core.planning.safety.guard import Guard, ScanReturns, Stop
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

EMPTY = World.from_obstacles([0, 0, 20, 20], [])
AHEAD = World.from_obstacles([0, 0, 20, 20], [Circle((6.6, 5.0), 1.0)])   # surface 1.6 m ahead of (5, 5)
SPEC = RobotSpec('r1', 'point_mass', (5.0, 5.0), (15.0, 5.0), 0.5)


def test_the_guard_stops_a_tick_into_the_radius_and_lets_a_robot_inside_move_away():
    guard, state = Guard(PointMass(), 0.5, PlannerParams()), np.array([5.0, 5.0])
    fast = np.array([25.0, 0.0])   # 1.25 m in one 0.05 s tick: ends 0.35 m from the surface
    assert np.all(guard.check(AHEAD, state, fast, 0.05, []) == 0.0) and guard.stop is Stop.OBSTACLE
    slow = np.array([1.0, 0.0])
    assert guard.check(AHEAD, state, slow, 0.05, []) is slow
    inside = np.array([5.3, 5.0])   # 0.3 m from the surface, nearer than the radius
    away = np.array([-1.0, 0.0])
    assert guard.check(AHEAD, inside, away, 0.05, []) is away


def test_a_robot_planning_in_its_scans_keeps_the_perception_margin_too():
    """A step ending 1 cm beyond the radius from a surface is let through on a map that is the truth and refused
    for a robot whose surfaces come from its scans (obstacle_margin, belief.PERCEPTION_MARGIN)."""
    state, step = np.array([5.0, 5.0]), np.array([1.8, 0.0])   # 0.09 m in one tick: ends 0.51 m from the surface
    exact = Guard(PointMass(), 0.5, PlannerParams())
    assert exact.check(AHEAD, state, step, 0.05, []) is step
    sensing = Guard(PointMass(), 0.5, PlannerParams())
    sensing.obstacle_margin = 0.02
    assert np.all(sensing.check(AHEAD, state, step, 0.05, []) == 0.0) and sensing.stop is Stop.OBSTACLE


def test_a_free_disc_learnt_in_one_world_is_not_trusted_in_a_new_one():
    """The planner node swaps the navigator's world when the map changes (a new obstacle): what the guard
    learnt was free in the old world (here 11 m round the robot) must be checked again in the new one."""
    nav = make_navigator('fastep', SPEC, 0.5, World.from_obstacles([0, 0, 20, 20], [Circle((15.0, 15.0), 1.0)]),
                         PlannerParams(), 0)
    state, fast = np.array([5.0, 5.0]), np.array([25.0, 0.0])   # 1.25 m in one tick
    assert nav.guard(state, fast, 0.05, []) is fast
    nav.world = AHEAD
    assert np.all(nav.guard(state, fast, 0.05, []) == 0.0) and 'obstacle is within the robot radius' in nav.reason


def test_the_guard_gives_way_to_another_robot_it_would_close_in_on():
    guard, state = Guard(PointMass(), 0.5, PlannerParams()), np.array([5.0, 5.0])
    other = OtherRobot('r2', (6.1, 5.0), radius=0.5)   # 1.1 m apart: radii 1 m + reach 0.1 m
    assert np.all(guard.check(EMPTY, state, np.array([1.0, 0.0]), 0.05, [other]) == 0.0)
    assert guard.stop is Stop.ROBOT and 'giving way to r2' in guard.reason
    away = np.array([-1.0, 0.0])
    assert guard.check(EMPTY, state, away, 0.05, [other]) is away


def test_the_guard_counts_a_mover_faster_than_the_robots_at_its_own_speed():
    guard, state, ahead = Guard(PointMass(), 0.5, PlannerParams()), np.array([5.0, 5.0]), np.array([1.0, 0.0])
    # 1.2 m apart, 1.15 m after the tick: clear of radii 1 m + a robot's reach 0.1 m (1 m/s), not of a mover
    # coming at 3 m/s (reach 0.2 m).
    slow = OtherRobot('r2', (6.2, 5.0), (-1.0, 0.0), 0.5)
    fast = OtherRobot('mover 0', (6.2, 5.0), (-3.0, 0.0), 0.5)
    assert guard.check(EMPTY, state, ahead, 0.05, [slow]) is ahead
    assert np.all(guard.check(EMPTY, state, ahead, 0.05, [fast]) == 0.0) and 'giving way to mover 0' in guard.reason


def test_detection_is_asked_again_when_the_world_changes():
    nav = make_navigator('fastep', SPEC, 0.5, EMPTY, PlannerParams(), 0)
    nav.set_goal((15.0, 5.0))
    position, goal = np.array([5.0, 5.0]), nav.goal
    assert goal is not None and not nav.blocked(position, goal, [])
    nav.world = AHEAD   # same position, same target: only the world is new
    assert nav.blocked(position, goal, [])


def test_a_navigator_steps_round_an_obstacle_that_appears_mid_run():
    nav = make_navigator('fastep', SPEC, 0.5, EMPTY, PlannerParams(), 0)
    nav.set_goal((15.0, 5.0))
    state, model, t = np.array([3.0, 5.0]), PointMass(), 0.0
    for _ in range(10):   # kinematic toward the goal in an empty world
        state = model.integrate(state, nav.update(t, state), 0.05)
        t += 0.05
    nav.world = AHEAD
    path = []
    while nav.mode.value not in ('arrived', 'failed') and t < 300.0:
        state = model.integrate(state, nav.update(t, state), 0.05)
        path.append(state.copy())
        t += 0.05
    assert nav.mode.value == 'arrived' and nav.activations >= 1
    assert float(AHEAD.obstacles.clearance(np.array(path)).min()) >= 0.5


def test_the_guard_stops_short_of_a_laser_return_the_belief_lacks_and_lets_the_robot_move_away():
    """Whatever perception made of a scan, the beams' ends are something: a return 0.4 m ahead, on an empty
    map, stops a step that ends within the radius of it; moving away from it goes."""
    guard, state = Guard(PointMass(), 0.5, PlannerParams()), np.array([5.0, 5.0])
    step = np.array([2.0, 0.0])                               # 0.1 m in one tick: ends 0.3 m from the return
    assert guard.check(EMPTY, state, step, 0.05, []) is step
    guard.scan_points = ScanReturns(np.array([[5.4, 5.0], [9.0, 9.0]]), state, 0.5)
    assert np.all(guard.check(EMPTY, state, step, 0.05, []) == 0.0) and guard.stop is Stop.OBSTACLE
    assert 'laser' in guard.reason
    away = np.array([-2.0, 0.0])
    assert guard.check(EMPTY, state, away, 0.05, []) is away


def test_the_returns_near_where_the_scan_was_taken_give_every_decision_all_of_them_give():
    """The guard reads only the returns near where the robot took the scan while it is within NEAR_ROOM of there
    (fewer numbers on the control tick): every stop and every go must be what all the returns decide."""
    from fastep_core.planning.safety.guard import NEAR_ROOM
    rng = np.random.default_rng(7)
    model, radius = PointMass(), 0.4
    decided = {True: 0, False: 0}
    for _ in range(2000):
        taken_at = rng.uniform(5.0, 15.0, 2)
        points = taken_at + rng.uniform(-2.0, 2.0, (40, 2))   # sparse: the one return that decides is often far
        returns = ScanReturns(points, taken_at, radius)
        assert 0 < len(returns.near) < len(points)
        state = taken_at + rng.uniform(-1.2, 1.2, 2) * NEAR_ROOM
        command = rng.uniform(-2.0, 2.0, 2)
        near, whole = Guard(model, radius, PlannerParams()), Guard(model, radius, PlannerParams())
        near.scan_points = returns
        whole.scan_points = ScanReturns(points, taken_at + 100.0, radius)   # far from here: all of them
        stopped = near.check(EMPTY, state, command, 0.05, []) is not command
        assert stopped == (whole.check(EMPTY, state, command, 0.05, []) is not command)
        decided[stopped] += 1
    assert min(decided.values()) > 20
