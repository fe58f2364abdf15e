"""The tractor-trailer model and its controller (fastep_core.kinematics.tractor_trailer)."""

import math

import numpy as np
import pytest

from fastep_core.kinematics import TractorTrailer, TractorTrailerController, hitch_angle, wrap_angle
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


def test_a_huge_heading_still_turns():
    """At 1e15 rad a float has 0.125 rad steps: each step's turn was rounded away (issue "Hardening", 24)."""
    model, command = TractorTrailer(), np.array([1.0, 1.0])
    huge = np.array([5.0, 5.0, 1e15, 1e15])
    same = np.array([5.0, 5.0, wrap_angle(1e15), wrap_angle(1e15)])
    for _ in range(20):
        huge, same = model.integrate(huge, command, 0.05), model.integrate(same, command, 0.05)
    assert np.array_equal(huge, same)
    assert wrap_angle(float(huge[2]) - wrap_angle(1e15)) == pytest.approx(1.0)   # 20 steps of 0.05 rad


def test_headings_within_the_limit_are_integrated_as_they_are():
    model = TractorTrailer()
    s = np.array([0.0, 0.0, 1000.0, 1000.5])
    after = model.integrate(s, np.array([1.0, 0.5]), 0.05)
    assert after[2] == pytest.approx(1000.025) and after[3] > 1000.0


def _arrival(states, target, tol=0.3):
    """Index of the first state within tol of target, and the path driven until then."""
    k = int(np.flatnonzero(np.hypot(*(states[:, :2] - target).T) < tol)[0])
    return k, float(np.hypot(*np.diff(states[:k + 1, :2], axis=0).T).sum())


@pytest.mark.parametrize('start, target', [
    ([5.0, 5.0, 0.0, 0.0], [45.0, 45.0]),
    ([25.0, 25.0, 0.0, 0.0], [15.0, 25.0]),       # straight behind
    ([25.0, 25.0, math.pi / 2, 0.0], [40.0, 10.0]),  # a 90 degree hitch angle at the start
    ([25.0, 25.0, 0.0, 0.0], [25.0, 27.0]),       # abeam, 2 m
    ([25.0, 25.0, 0.0, 0.0], [27.0, 25.0]),       # ahead, 2 m
])
def test_minimum_speed_arrives_sooner_on_the_same_path(start, target):
    """Issue 14, item 7: the paper's law needs 17-19 s for a target 2 m away; with min_speed 0.3 m/s, 6 s at most.
    The steering is the law's, so the path and the hitch angle stay as they were until the robot arrives."""
    model, target = TractorTrailer(1.0, 1.0, 0.0), np.array(target)
    paper = drive(model, TractorTrailerController(model, 0.1, 1.0), start, target, steps=8000)
    fast = drive(model, TractorTrailerController(model, 0.1, 1.0, min_speed=0.3), start, target, steps=8000)
    (k_paper, path_paper), (k_fast, path_fast) = _arrival(paper, target), _arrival(fast, target)
    assert k_fast < k_paper
    assert path_fast == pytest.approx(path_paper, rel=0.03)
    if np.hypot(*(target - start[:2])) <= 2.0:
        assert k_fast * 0.05 <= 6.0 < k_paper * 0.05
    assert np.degrees(np.abs([hitch_angle(s) for s in fast[200:k_fast + 1]])).max(initial=0.0) < 80.0



def test_integrate_in_floats_is_the_array_form_bit_for_bit():
    """integrate() and velocity() compute in floats what the array form of the RK4 step computes on each element,
    in the same order: the same floats (wound-up headings, which are normalised first, included)."""
    import fastep_core.kinematics.tractor_trailer as tt

    def array_form(model, state, command, dt):
        s = np.asarray(state, dtype=float)
        if abs(s[2]) > tt.HEADING_LIMIT or abs(s[3]) > tt.HEADING_LIMIT:
            s = np.array([s[0], s[1], tt.wrap_angle(float(s[2])), tt.wrap_angle(float(s[3]))])
        k1 = model.derivative(s, command)
        k2 = model.derivative(s + 0.5 * dt * k1, command)
        k3 = model.derivative(s + 0.5 * dt * k2, command)
        k4 = model.derivative(s + dt * k3, command)
        return s + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)

    rng = np.random.default_rng(7)
    for model in (tt.TractorTrailer(), tt.TractorTrailer(1.3, 0.7, 0.25)):
        for k in range(3000):
            state = rng.normal(size=4) * np.array([30.0, 30.0, 4.0, 4.0])
            if k % 100 == 0:
                state[2 + k % 2] = 1e6
            command = rng.normal(size=2) * np.array([1.0, 1.5])
            dt = (0.05, 0.1, 0.013)[k % 3]
            assert np.array_equal(model.integrate(state, command, dt), array_form(model, state, command, dt))
            assert np.array_equal(model.velocity(state, command), model.derivative(state, command)[:2])
