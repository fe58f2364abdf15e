"""The velocity smoother, the last stage before cmd_vel (planning/safety/smoother.py): ramps from what the base does
after a pause, the limits of each model, the emergency stop's braking, the reverse cap, runtime limits, 0 =
unlimited."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.errors import ParameterError
from fastep_core.kinematics import PointMass, TractorTrailer
from fastep_core.kinematics.diff_drive import DiffDrive
from fastep_core.planning import PlannerParams
from fastep_core.planning.safety.smoother import VelocitySmoother

P = PlannerParams()
DT = P.dt
A, ALPHA = P.max_acceleration, P.max_turn_acceleration
MODELS = {'diff_drive': DiffDrive(P.max_speed, P.max_turn_rate), 'tractor_trailer': TractorTrailer(),
          'point_mass': PointMass()}


def smoother(model: str, **params: float) -> VelocitySmoother:
    return VelocitySmoother.for_model(MODELS[model], P.with_overrides(params).limits)


def drive(s: VelocitySmoother, command: tuple[float, float], ticks: int, elapsed: float = DT) -> np.ndarray:
    return np.array([s.smooth(np.array(command), elapsed) for _ in range(ticks)])


@pytest.mark.parametrize('pause', [DT, 0.5, 3.0, 1e6])
def test_after_a_pause_of_any_length_the_next_command_ramps_from_rest(pause):
    """The report: after a gap the next command jumped from 0 to 1.0 m/s (47-50 m/s^2 at the base)."""
    s = smoother('diff_drive')
    first = s.smooth(np.array([1.0, 0.0]), pause)
    assert first[0] == pytest.approx(A * DT) and first[1] == 0.0
    rest = drive(s, (1.0, 0.0), 20)
    assert np.diff(np.concatenate([[first[0]], rest[:, 0]])).max() <= A * DT * (1 + 1e-9)
    assert rest[-1, 0] == pytest.approx(1.0)   # it does get there: 1.0 / (A dt) = 8 ticks


def test_after_a_pause_it_ramps_from_the_velocity_odometry_reports():
    s = smoother('diff_drive')
    drive(s, (1.0, 0.0), 20)
    s.reset(np.array([0.4, 0.0]))   # odometry: the base slowed down during the gap (its command timeout)
    assert s.smooth(np.array([1.0, 0.0]), 2.0)[0] == pytest.approx(0.4 + A * DT)
    s.reset(np.array([math.nan, 0.0]))   # no usable twist: standing still
    assert s.smooth(np.array([1.0, 0.0]), 2.0)[0] == pytest.approx(A * DT)


def test_a_point_mass_ramps_the_norm_of_its_velocity_change():
    s = smoother('point_mass')
    first = s.smooth(np.array([0.6, 0.8]), 10.0)
    assert np.hypot(*first) == pytest.approx(A * DT) and first[1] / first[0] == pytest.approx(0.8 / 0.6)
    drive(s, (0.6, 0.8), 20)
    turn = s.smooth(np.array([-0.8, 0.6]), DT)   # a right-angle change of direction at full speed
    assert np.hypot(*(turn - np.array([0.6, 0.8]))) == pytest.approx(A * DT)


@pytest.mark.parametrize('model', sorted(MODELS))
def test_every_command_keeps_every_limit_of_its_model(model):
    s = smoother(model)
    rng = np.random.default_rng(3)
    commands = rng.uniform(-3.0, 3.0, (400, 2))
    elapsed = rng.choice([0.0, 0.01, DT, 0.3, 5.0], 400)
    sent = np.array([s.smooth(c, e) for c, e in zip(commands, elapsed)])
    change = np.diff(np.vstack([np.zeros(2), sent]), axis=0)
    window = np.minimum(elapsed, DT)
    if model == 'point_mass':
        assert (np.hypot(*change.T) <= A * window * (1 + 1e-9) + 1e-12).all()
        assert (np.hypot(*sent.T) <= P.max_speed * (1 + 1e-9)).all()
        assert sent[:, 0].min() < -P.max_reverse_speed   # no rear: no reverse cap
    else:
        assert (np.abs(change[:, 0]) <= A * window * (1 + 1e-9) + 1e-12).all()
        assert (np.abs(change[:, 1]) <= ALPHA * window * (1 + 1e-9) + 1e-12).all()
        assert (sent[:, 0] <= P.max_speed * (1 + 1e-9)).all()
        assert (sent[:, 0] >= -P.max_reverse_speed * (1 + 1e-9)).all()
        assert np.abs(sent[:, 1]).max() <= P.max_turn_rate * (1 + 1e-9) or model == 'tractor_trailer'
        held = drive(s, (0.2, 3.0), 60)[-1, 1]
        # A tractor-trailer's turn rate is its steering's (v tan(phi) / L): it has no max_turn_rate.
        assert held == pytest.approx(P.max_turn_rate if model == 'diff_drive' else 3.0)


def test_the_speed_caps_keep_a_steered_robots_curvature():
    s = smoother('diff_drive', max_acceleration=0.0, max_turn_acceleration=0.0)
    assert s.smooth(np.array([2.0, 1.0]), DT) == pytest.approx([1.0, 0.5])      # max_speed
    assert s.smooth(np.array([0.5, 4.0]), DT) == pytest.approx([0.25, 2.0])     # max_turn_rate
    assert s.smooth(np.array([-1.0, 0.4]), DT) == pytest.approx([-0.25, 0.1])   # max_reverse_speed


def test_never_reverses_faster_than_max_reverse_speed():
    """The report: it reversed at 1.0 m/s with the rear 90 degrees of its laser blind."""
    for model in ('diff_drive', 'tractor_trailer'):
        s = smoother(model, max_reverse_speed=0.2)
        sent = drive(s, (-1.0, 0.0), 40)
        assert sent[:, 0].min() == pytest.approx(-0.2) and sent[-1, 0] == pytest.approx(-0.2)
    s = smoother('diff_drive', max_reverse_speed=0.0)   # 0: unlimited
    assert drive(s, (-1.0, 0.0), 40)[-1, 0] == pytest.approx(-1.0)


def test_only_the_emergency_stop_brakes_harder_at_emergency_deceleration():
    normal, emergency = smoother('diff_drive'), smoother('diff_drive')
    for s in (normal, emergency):
        drive(s, (1.0, 1.0), 20)
    stop = np.zeros(2)
    slow = np.array([normal.smooth(stop, DT) for _ in range(30)])
    hard = np.array([emergency.smooth(stop, DT, emergency=True) for _ in range(30)])
    decel = P.emergency_deceleration
    assert decel == 2 * A   # the documented default
    assert (-np.diff(np.concatenate([[1.0], slow[:, 0]]))).max() == pytest.approx(A * DT)
    assert (-np.diff(np.concatenate([[1.0], hard[:, 0]]))).max() == pytest.approx(decel * DT)
    assert int(np.argmax(hard[:, 0] == 0.0)) + 1 == math.ceil(1.0 / (decel * DT))   # 4 ticks, 0.1 m
    assert int(np.argmax(slow[:, 0] == 0.0)) + 1 == math.ceil(1.0 / (A * DT))       # 8 ticks
    assert (hard[:, 1] / np.where(hard[:, 0] > 0, hard[:, 0], 1.0))[hard[:, 0] > 0] == pytest.approx(1.0)
    instant = smoother('diff_drive', emergency_deceleration=0.0)   # 0: the stop is immediate
    drive(instant, (1.0, 0.0), 20)
    assert np.all(instant.smooth(stop, DT, emergency=True) == 0.0)


def test_emergency_deceleration_is_at_least_max_acceleration():
    with pytest.raises(ParameterError, match='emergency_deceleration'):
        PlannerParams(max_acceleration=3.0, emergency_deceleration=2.0)
    with pytest.raises(ParameterError, match='emergency_deceleration'):
        P.with_overrides({'max_acceleration': 6.0})
    assert P.with_overrides({'max_acceleration': 6.0, 'emergency_deceleration': 6.0}).emergency_deceleration == 6
    assert PlannerParams(max_acceleration=3.0, emergency_deceleration=0.0).emergency_deceleration == 0.0
    assert {'max_reverse_speed', 'emergency_deceleration'} <= set(PlannerParams.descriptions())


def test_zero_limits_are_unlimited():
    s = smoother('diff_drive', max_speed=0.0, max_reverse_speed=0.0, max_turn_rate=0.0, max_acceleration=0.0,
                 max_turn_acceleration=0.0, emergency_deceleration=0.0)
    for command in ([5.0, 9.0], [-7.0, -3.0], [0.0, 0.0]):
        assert np.all(s.smooth(np.array(command), DT) == command)
    p = smoother('point_mass', max_speed=0.0, max_acceleration=0.0)
    assert np.all(p.smooth(np.array([4.0, -3.0]), DT) == [4.0, -3.0])


def test_no_time_no_change_and_a_command_that_is_not_finite_is_a_stop():
    s = smoother('diff_drive')
    drive(s, (1.0, 0.0), 20)
    for elapsed in (0.0, -1.0, math.nan):
        assert s.smooth(np.array([0.0, 2.0]), elapsed) == pytest.approx([1.0, 0.0])
    assert s.smooth(np.array([math.nan, 0.0]), DT) == pytest.approx([1.0 - A * DT, 0.0])


@pytest.mark.parametrize('name, value, command, expect', [
    ('max_speed', 0.5, (1.0, 0.0), (0.5, 0.0)),
    ('max_speed', 1.0, (1.0, 0.0), (1.0, 0.0)),   # set to its own value: nothing changes (the 0.13 m/s report)
    ('max_reverse_speed', 0.1, (-1.0, 0.0), (-0.1, 0.0)),
    ('max_turn_rate', 0.5, (0.0, 3.0), (0.0, 0.5)),
])
def test_a_speed_limit_set_at_runtime_takes_effect_as_set(name, value, command, expect):
    s = smoother('diff_drive')
    drive(s, (1.0, 0.0), 20)
    s.retune(P.with_overrides({name: value}).limits)
    sent = drive(s, command, 80)
    assert sent[-1] == pytest.approx(expect)
    change = np.diff(np.vstack([[1.0, 0.0], sent]), axis=0)   # reached within the acceleration limits
    assert np.abs(change[:, 0]).max() <= A * DT * (1 + 1e-9) and np.abs(change[:, 1]).max() <= ALPHA * DT * (1 + 1e-9)
    if name == 'max_speed' and value == 1.0:
        assert np.all(sent[:, 0] == 1.0)


@pytest.mark.parametrize('name, value, rate', [
    ('max_acceleration', 1.0, 1.0),         # from (1 m/s, 1 rad/s) to rest: 1.0 m/s^2 binds (3.2 rad/s^2 does not)
    ('max_turn_acceleration', 1.0, 1.0),    # 1.0 rad/s^2 binds (2.5 m/s^2 does not)
    ('emergency_deceleration', 8.0, 8.0),   # the emergency stop: 8 m/s^2 (and 3.2 x 8 / 2.5 rad/s^2)
])
def test_an_acceleration_limit_set_at_runtime_takes_effect_as_set(name, value, rate):
    s = smoother('diff_drive')
    drive(s, (1.0, 1.0), 40)
    s.retune(P.with_overrides({name: value}).limits)
    after = s.smooth(np.zeros(2), DT, emergency=name == 'emergency_deceleration')
    # One factor moves both components (the curvature stays), so the tighter limit sets the pace of both.
    assert (1.0 - after) / DT == pytest.approx([rate, rate])
