"""The point-mass model and its controller (fastep_core.kinematics.point_mass)."""

import math

import numpy as np
import pytest

from fastep_core.kinematics import PointMass, PointMassController, lyapunov
from fastep_testing.closed_loop import drive


@pytest.mark.parametrize('max_speed', [0.0, 1.0])
def test_point_mass_lyapunov_decreases_and_converges(max_speed):
    target = np.array([45.0, 45.0])
    states = drive(PointMass(), PointMassController(0.1, 0.1, max_speed), [5.0, 5.0], target)
    v = np.array([lyapunov(s, target) for s in states])
    assert np.all(np.diff(v) < 0)
    assert v[-1] < 1e-3


def test_point_mass_speed_limit_keeps_direction():
    ctrl = PointMassController(0.1, 0.1, max_speed=1.0)
    u = ctrl.command(np.array([0.0, 0.0]), np.array([30.0, 40.0]), 0.05)
    assert np.hypot(*u) == pytest.approx(1.0)
    assert u[1] / u[0] == pytest.approx(40 / 30)


def test_point_mass_equal_gains_move_straight():
    states = drive(PointMass(), PointMassController(0.1, 0.1, 1.0), [5.0, 45.0], np.array([45.0, 5.0]), steps=600)
    # On the line x + y = 50.
    assert np.abs(states[:, 0] + states[:, 1] - 50.0).max() < 1e-9


# A minimum approach speed (issue 14, item 7: near obstacles eq. 12 crawled at 0.01-0.17 m/s, 35 s for 2 m).

def arrival_time(controller, start, target, tol, dt=0.05, steps=20000):
    """Simulated seconds until the point mass is within tol of target (inf if never within `steps` ticks)."""
    states = drive(PointMass(), controller, start, np.array(target), dt=dt, steps=steps)
    within = np.flatnonzero(np.hypot(*(states[:, :2] - target).T) <= tol)
    return within[0] * dt if len(within) else math.inf


@pytest.mark.parametrize('min_speed, max_speed', [(0.2, 1.0), (0.3, 1.0), (0.5, 0.0), (2.0, 0.25)])
@pytest.mark.parametrize('tol', [0.3, 0.1, 0.0])
def test_arrival_within_the_discrete_bound(min_speed, max_speed, tol):
    """Equal gains: within tol of a target d0 away after at most (d0 - tol) / min(m, max_speed) + dt seconds,
    exactly on it (tol 0) included; eq. 12 alone never gets there."""
    dt, d0 = 0.05, 2.0
    s = min(min_speed, max_speed) if max_speed > 0 else min_speed
    t = arrival_time(PointMassController(0.1, 0.1, max_speed, min_speed), [3.0, 4.0], [3.0 + d0, 4.0], tol, dt)
    assert t <= (d0 - tol) / s + dt + 1e-9
    if tol == 0.0:
        assert arrival_time(PointMassController(0.1, 0.1, max_speed), [3.0, 4.0], [3.0 + d0, 4.0], tol, dt) \
            == math.inf


def test_arrival_within_the_continuous_bound_with_unequal_gains():
    """(A / a) d0 / m with a, A the smaller and larger gain (dt small enough to stand for continuous time)."""
    ctrl = PointMassController(0.1, 0.3, 0.0, 0.2)
    start, target = np.array([0.0, 0.0]), np.array([1.2, 1.6])   # d0 = 2
    assert arrival_time(ctrl, start, target, 1e-3, dt=0.002, steps=200_000) <= 3.0 * 2.0 / 0.2


def test_eq12_before_the_paper_without_a_minimum_speed():
    """The crawl: 2 m from a waypoint eq. 12 needs 19 s to come within waypoint_tolerance (0.3 m)."""
    t = arrival_time(PointMassController(0.1, 0.1, 1.0), [0.0, 0.0], [2.0, 0.0], 0.3)
    assert t == pytest.approx(math.log(2.0 / 0.3) / 0.1, abs=0.1)


def test_minimum_speed_keeps_the_direction_and_the_speed_limit_and_v_decreases():
    rng = np.random.default_rng(14)
    for _ in range(500):
        gains, min_speed, max_speed = rng.uniform(0.01, 1.0, 2), rng.uniform(0.0, 2.0), rng.choice([0.0, 1.0])
        state, target = rng.uniform(-5, 5, 2), rng.uniform(-5, 5, 2)
        u = PointMassController(*gains, max_speed, min_speed).command(state, target, 0.05)
        eq12 = gains * (target - state)
        speed, distance = np.hypot(*u), np.hypot(*(target - state))
        assert u @ eq12 > 0 and abs(u[0] * eq12[1] - u[1] * eq12[0]) <= 1e-9 * np.hypot(*eq12) * speed
        assert max_speed == 0 or speed <= max_speed + 1e-12
        assert speed == pytest.approx(min(max(np.hypot(*eq12), min(min_speed, distance / 0.05)),
                                          max_speed or math.inf))
        assert (target - state) @ u > 0   # dV/dt = -e . u < 0 (Theorem 1)


@pytest.mark.parametrize('max_speed', [0.0, 1.0])
def test_no_minimum_speed_is_eq12_bit_for_bit(max_speed):
    rng = np.random.default_rng(7)
    for _ in range(200):
        state, target = rng.uniform(-30, 30, 2), rng.uniform(-30, 30, 2)
        paper = PointMassController(0.1, 0.1, max_speed).command(state, target, 0.05)
        assert np.array_equal(PointMassController(0.1, 0.1, max_speed, 0.0).command(state, target, 0.05), paper)
        u = np.array([0.1 * (target[0] - state[0]), 0.1 * (target[1] - state[1])])
        if max_speed == 0.0 or np.hypot(*u) <= max_speed:
            assert np.array_equal(paper, u)
