import math

import numpy as np
import pytest

from fastep_core.kinematics import (PointMass, PointMassController, TractorTrailer, TractorTrailerController,
                                    hitch_angle, lyapunov)


def drive(model, ctrl, state, target, dt=0.05, steps=4000):
    states = [np.asarray(state, float)]
    ctrl.reset(states[0], target)
    for _ in range(steps):
        states.append(model.integrate(states[-1], ctrl.command(states[-1], target, dt), dt))
    return np.array(states)


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


@pytest.mark.parametrize('start, target', [
    ([5.0, 5.0, 0.0, 0.0], [45.0, 45.0]),
    ([5.0, 45.0, 0.0, 0.0], [45.0, 5.0]),
    ([25.0, 25.0, 0.0, 0.0], [15.0, 25.0]),       # target straight behind: must turn around
    ([25.0, 25.0, math.pi / 2, 0.0], [40.0, 10.0]),  # starts with a 90 degree hitch angle
    ([25.0, 25.0, 0.0, 0.0], [25.0, 27.0]),       # target abeam, inside the turning circle of K = 1
])
def test_tractor_trailer_reaches_target_without_jackknife(start, target):
    model = TractorTrailer(1.0, 1.0, 0.0)
    ctrl = TractorTrailerController(model, speed_gain=0.1, max_speed=1.0)
    states = drive(model, ctrl, start, np.array(target), steps=8000)
    assert np.hypot(*(states[-1, :2] - target)) < 0.3
    hitch = np.degrees(np.abs([hitch_angle(s) for s in states]))
    # Once the start transient is over the hitch angle stays far from jack-knifing.
    assert hitch[200:].max() < 80.0


def test_tractor_trailer_straight_run_keeps_trailer_aligned():
    model = TractorTrailer()
    s = np.array([0.0, 0.0, 0.3, 0.3])
    for _ in range(100):
        s = model.integrate(s, np.array([1.0, 0.0]), 0.05)
    assert s[2] == pytest.approx(0.3) and s[3] == pytest.approx(0.3)
    assert s[:2] == pytest.approx([5 * math.cos(0.3), 5 * math.sin(0.3)])


def test_steering_is_bounded_by_70_degrees():
    ctrl = TractorTrailerController(TractorTrailer())
    for xi in (-50.0, -1.0, 0.0, 2.0, 50.0):
        for rel in np.linspace(-3.0, 3.0, 13):
            ctrl.xi = xi
            assert abs(ctrl.steering(np.array([0.0, 0.0, 0.0, rel]))) < math.radians(70.0) + 1e-12
