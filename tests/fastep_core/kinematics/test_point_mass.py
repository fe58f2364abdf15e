"""The point-mass model and its controller (fastep_core.kinematics.point_mass)."""

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
