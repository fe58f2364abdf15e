"""Yielding to movers over a horizon (planning/safety/yielding.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.kinematics import DiffDrive, PointMass, TractorTrailer
from fastep_core.planning.others import OtherRobot, OtherRobots
from fastep_core.planning.safety.yielding import Yielding, closest_approach, predicted_positions

MARGIN = 0.1


def keeps_clear(model, state, command, mover, horizon=3.0, radius=0.5):
    """Drive command and the mover tick by tick (0.01 s) with the model itself: the smallest gap - reach."""
    position, centre = np.array(state, dtype=float), np.array(mover.position, dtype=float)
    worst = math.inf
    for _ in range(int(horizon / 0.01)):
        position = model.integrate(position, command, 0.01)
        centre = centre + np.array(mover.velocity) * 0.01
        worst = min(worst, math.hypot(*(position[:2] - centre)) - radius - mover.radius - MARGIN)
    return worst


@pytest.mark.parametrize('model, state, command', [
    (PointMass(), [0.0, 0.0], [0.6, -0.3]),
    (DiffDrive(), [1.0, 2.0, 0.4], [0.8, 0.5]),
    (DiffDrive(), [1.0, 2.0, -2.0], [-0.5, -1.0]),
    (DiffDrive(), [1.0, 2.0, 0.0], [0.7, 0.0]),
])
def test_predicted_positions_follow_the_model(model, state, command):
    times = np.linspace(0.0, 3.0, 31)
    predicted = predicted_positions(model, np.array(state), np.array([command]), times)[0]
    probe = np.array(state, dtype=float)
    for k, t in enumerate(times):
        assert np.allclose(predicted[k], probe[:2], atol=1e-6), t
        for _ in range(10):
            probe = model.integrate(probe, np.array(command), 0.01)


def test_a_tractor_is_predicted_along_its_arc_within_centimetres():
    model = TractorTrailer()
    state = np.array([0.0, 0.0, 0.3, 0.3])   # trailer in line: the tractor's turn rate is constant
    command = np.array([0.8, 0.2])
    predicted = predicted_positions(model, state, command[None], np.array([0.0, 1.0]))[0]
    probe = state
    for _ in range(100):
        probe = model.integrate(probe, command, 0.01)
    assert math.hypot(*(predicted[1] - probe[:2])) < 0.02


def test_closest_approach_is_exact_between_samples():
    relative = np.array([[[-1.0, 0.3], [1.0, 0.3]], [[2.0, 2.0], [3.0, 2.0]]])
    assert np.allclose(closest_approach(relative), [0.3, math.hypot(2.0, 2.0)])


def test_no_mover_near_leaves_the_command_alone():
    yielding = Yielding(PointMass(), 0.5, 3.0, MARGIN, 1.0)
    command = np.array([1.0, 0.0])
    robots = [OtherRobot('r2', (1.5, 0.0), (-1.0, 0.0))]                    # a robot, not a mover
    far = [OtherRobot('mover 0', (40.0, 0.0), (-1.0, 0.0), 0.5, mover=True)]   # too far to matter in 3 s
    for others in (robots, far, []):
        assert yielding.check(np.zeros(2), command, others).command is command
    assert Yielding(PointMass(), 0.5, 0.0, MARGIN, 1.0).check(
        np.zeros(2), command, [OtherRobot('mover 0', (1.5, 0.0), (-1.0, 0.0), 0.5, mover=True)]).command is command


def test_a_robot_slows_down_for_a_mover_crossing_ahead():
    """Robot east at 1 m/s; a mover from the south crosses its line 3 m ahead when the robot would be there."""
    model, state, command = PointMass(), np.zeros(2), np.array([1.0, 0.0])
    mover = OtherRobot('mover 0', (3.0, -3.0), (0.0, 1.0), 0.5, mover=True)
    assert keeps_clear(model, state, command, mover) < 0   # as commanded, it would meet the mover
    result = Yielding(model, 0.5, 3.0, MARGIN, 1.0).check(state, command, [mover])
    assert result.kind in ('yielding', 'waiting') and 'mover 0' in result.reason
    assert keeps_clear(model, state, result.command, mover) >= -1e-6
    # slower, along the same line
    assert np.allclose(result.command / max(np.linalg.norm(result.command), 1e-12), [1.0, 0.0]) or \
        not result.command.any()


@pytest.mark.parametrize('model, state', [(PointMass(), np.zeros(2)), (DiffDrive(), np.array([0.0, 0.0, 0.0]))])
def test_a_robot_a_mover_would_run_into_gets_out_of_its_way(model, state):
    """Standing is no answer to a mover coming straight at the robot: it moves aside."""
    mover = OtherRobot('mover 3', (0.0, 3.0), (0.0, -1.0), 0.5, mover=True)
    assert keeps_clear(model, state, np.zeros(2), mover) < 0
    result = Yielding(model, 0.5, 3.0, MARGIN, 1.0, 2.0).check(state, np.zeros(2), [mover])
    assert result.kind == 'evading' and result.reason == 'getting out of the way of mover 3'
    assert keeps_clear(model, state, result.command, mover) > keeps_clear(model, state, np.zeros(2), mover)


def test_a_move_the_guard_refuses_is_never_the_way_out():
    model, state = PointMass(), np.zeros(2)
    mover = OtherRobot('mover 3', (0.0, 3.0), (0.0, -1.0), 0.5, mover=True)
    yielding = Yielding(model, 0.5, 3.0, MARGIN, 1.0)
    free = yielding.check(state, np.zeros(2), [mover]).command
    # a wall there: the guard refuses every move within 90 degrees of that one
    walled = yielding.check(state, np.zeros(2), [mover], allowed=lambda c: float(c @ free) <= 0.0)
    assert walled.kind == 'evading' and float(walled.command @ free) <= 0.0
    assert keeps_clear(model, state, walled.command, mover) > keeps_clear(model, state, np.zeros(2), mover)


def test_movers_are_found_among_the_views_of_a_tick():
    robots = [OtherRobot('r1', (0.0, 0.0)), OtherRobot('r2', (5.0, 0.0)),
              OtherRobot('mover 0', (2.0, 0.0), (1.0, 0.0), 0.4, mover=True)]
    views = OtherRobots.views(robots, 2)
    assert [o.name for o in views[0].movers()] == ['mover 0'] == [o.name for o in views[1].movers()]
    assert OtherRobots.views(robots[:2])[0].movers() == []
