"""The differential-drive model and its controller (fastep_core.kinematics.diff_drive)."""

import math

import numpy as np
import pytest

from fastep_core.kinematics.diff_drive import DiffDrive, DiffDriveController, heading_error
from fastep_core.kinematics.model import RobotModel
from fastep_core.kinematics.tractor_trailer import wrap_angle

DT = 0.05


def run(controller, start, target, dt=DT, tolerance=0.01, steps=6000):
    """States (n, 3) and commands (n - 1, 2) until the base is within tolerance of target (or steps ran)."""
    model = DiffDrive(controller.max_speed, controller.max_turn_rate)
    target = np.asarray(target, dtype=float)
    states, commands = [np.asarray(start, dtype=float)], []
    for _ in range(steps):
        if math.hypot(*(target - states[-1][:2])) <= tolerance:
            break
        command = controller.command(states[-1], target, dt)
        controller.applied(command)
        commands.append(command)
        states.append(model.integrate(states[-1], command, dt))
    return np.array(states), np.array(commands).reshape(-1, 2)


def fine_reference(state, command, dt, n=4000):
    """The unicycle ODE by classical Runge-Kutta in n sub-steps (error ~ (dt/n)^4)."""
    v, omega = command
    s = np.array(state, dtype=float)

    def f(s):
        return np.array([v * math.cos(s[2]), v * math.sin(s[2]), omega])

    h = dt / n
    for _ in range(n):
        k1 = f(s)
        k2 = f(s + 0.5 * h * k1)
        k3 = f(s + 0.5 * h * k2)
        k4 = f(s + h * k3)
        s = s + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return s


def test_declares_what_it_can_do():
    model: RobotModel = DiffDrive()
    assert (model.holonomic, model.turns_in_place, model.reverses, model.trailer) == (False, True, True, False)
    assert model.state_size == 3


@pytest.mark.parametrize('command', [(1.0, 0.0), (0.7, 1e-7), (0.5, 1.3), (-0.8, -2.0), (0.0, 1.5), (1.0, 40.0)])
def test_integration_is_exact_against_a_fine_step_reference(command):
    model = DiffDrive()
    state = np.array([3.0, -2.0, 2.5])
    dt = 0.5   # long, so an approximate (Euler, midpoint) step would be far off
    exact = model.integrate(state, np.array(command), dt)
    reference = fine_reference(state, command, dt)
    assert exact[:2] == pytest.approx(reference[:2], abs=1e-10)
    assert wrap_angle(exact[2] - reference[2]) == pytest.approx(0.0, abs=1e-10)
    assert -math.pi < exact[2] <= math.pi


def test_a_straight_run_is_exact():
    after = DiffDrive().integrate(np.array([1.0, 2.0, 0.0]), np.array([2.0, 0.0]), 0.25)
    assert after.tolist() == [1.5, 2.0, 0.0]


def test_the_base_saturates_speed_and_turn_rate():
    model = DiffDrive(max_speed=0.5, max_turn_rate=1.0)
    state = np.array([0.0, 0.0, 0.0])
    assert model.integrate(state, np.array([3.0, 0.0]), 1.0)[0] == pytest.approx(0.5)
    assert model.integrate(state, np.array([0.0, -4.0]), 0.5)[2] == pytest.approx(-0.5)
    assert model.velocity(np.array([0.0, 0.0, math.pi / 2]), np.array([-2.0, 0.0])) == pytest.approx([0.0, -0.5])


STARTS = [(r * math.cos(b), r * math.sin(b)) for r in (0.4, 3.0, 20.0) for b in np.linspace(0, 2 * math.pi, 6,
                                                                                            endpoint=False)]
HEADINGS = list(np.linspace(-math.pi, math.pi, 12, endpoint=False)) + [math.pi]


@pytest.mark.parametrize('start', STARTS)
def test_converges_from_every_heading(start):
    """From every position of the grid and every heading (the target straight behind included), the sampled
    closed loop with every limit on reaches the target; the distance never grows (V = rho^2/2 non-increasing);
    the heading error dies out; the commands keep the speed, turn-rate and acceleration limits."""
    target = np.array([0.0, 0.0])
    for heading in HEADINGS:
        controller = DiffDriveController()
        states, commands = run(controller, [start[0], start[1], heading], target)
        rho = np.hypot(*(target - states[:, :2]).T)
        assert rho[-1] <= 0.01, (start, heading)
        assert np.all(np.diff(rho) <= 1e-12), (start, heading)
        assert np.abs(commands[:, 0]).max() <= controller.max_speed + 1e-12
        assert np.abs(commands[:, 1]).max() <= controller.max_turn_rate + 1e-12
        change = np.diff(np.vstack([np.zeros(2), commands]), axis=0)
        assert np.abs(change[:, 0]).max() <= controller.max_acceleration * DT * (1 + 1e-9)
        assert np.abs(change[:, 1]).max() <= controller.max_turn_acceleration * DT * (1 + 1e-9)
        assert commands[:, 0].min() >= 0.0   # it turns first and drives forward


def test_target_straight_behind_turns_on_the_spot_then_drives_straight():
    controller = DiffDriveController()
    states, _ = run(controller, [10.0, 0.0, 0.0], [0.0, 0.0])
    alpha = np.array([heading_error(s, np.zeros(2)) if math.hypot(*s[:2]) > 1e-6 else 0.0 for s in states])
    turning = np.abs(alpha) >= controller.drive_within
    assert turning[0] and np.hypot(*(states[turning][:, :2] - [10.0, 0.0]).T).max() < 1e-9
    # After the turn it stays close to the line it faces (the turn-first factor h of the module docstring).
    assert np.abs(states[:, 1]).max() < 0.15


def test_the_heading_error_decays_exponentially_without_acceleration_limits():
    """alpha' = -k2 alpha / s (the proof): with s = 1 (no saturation) alpha halves in ln 2 / k2 seconds."""
    controller = DiffDriveController(max_acceleration=0.0, max_turn_acceleration=0.0, max_turn_rate=0.0)
    target = np.array([20.0, 0.0])
    states, _ = run(controller, [0.0, 0.0, 0.4], target, dt=0.001, steps=2000)
    alpha = np.array([heading_error(s, target) for s in states])
    t = np.arange(len(alpha)) * 0.001
    # alpha(0) = bearing - heading = -0.4; sampled at dt, alpha shrinks by (1 - k2 dt) a tick: within 0.5 %.
    assert alpha[1000] == pytest.approx(-0.4 * math.exp(-controller.turn_gain * t[1000]), rel=5e-3)


def test_min_speed_is_a_floor_on_the_approach_speed():
    slow, floored = DiffDriveController(), DiffDriveController(min_speed=0.3)
    state, target = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0])
    assert slow.law(state, target, DT)[0] == pytest.approx(0.1)
    assert floored.law(state, target, DT)[0] == pytest.approx(0.3)
    # Within one tick's travel the floor is rho / dt: the next step lands on the target, not past it.
    assert floored.law(state, np.array([0.01, 0.0]), DT)[0] == pytest.approx(0.01 / DT)
    t_slow = len(run(DiffDriveController(), [0, 0, 0], [5, 0])[1])
    states, _ = run(DiffDriveController(min_speed=0.3), [0, 0, 0], [5, 0])
    assert len(states) - 1 < t_slow / 2
    assert np.all(np.diff(5.0 - states[:, 0]) <= 1e-12)   # never past the target


def test_the_acceleration_limit_starts_from_the_applied_command():
    """A guarded stop (zeros applied) makes the next command start from rest, not from the last one computed."""
    controller = DiffDriveController()
    state, target = np.array([0.0, 0.0, 0.0]), np.array([30.0, 0.0])
    for _ in range(40):
        controller.applied(controller.command(state, target, DT))
    assert controller.last[0] == pytest.approx(1.0)
    controller.applied(np.zeros(2))
    assert controller.command(state, target, DT)[0] == pytest.approx(controller.max_acceleration * DT)
