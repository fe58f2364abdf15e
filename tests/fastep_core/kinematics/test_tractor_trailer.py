"""The tractor-trailer model and its controller (fastep_core.kinematics.tractor_trailer)."""

import math

import numpy as np
import pytest

from fastep_core.kinematics import TractorTrailer, TractorTrailerController, hitch_angle
from fastep_testing.closed_loop import drive


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
