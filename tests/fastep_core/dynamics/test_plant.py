"""The plants: kinematic as before, physics deterministic, its odometry drifting on slip, its command timeout,
its controller's limits, and mujoco imported only when a physics plant is made."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from fastep_core.dynamics import (
    BaseController,
    KinematicPlant,
    PhysicsPlant,
    make_plant,
    odometry_generator,
    preset,
)
from fastep_core.errors import ParameterError
from fastep_core.kinematics import DiffDrive, PointMass

DT = 0.05


def _drive(plant: PhysicsPlant, commands: list[tuple[float, float]], ticks: int) -> list[np.ndarray]:
    states = []
    for v, omega in commands:
        for _ in range(ticks):
            plant.step(np.array([v, omega]), DT)
            states.append(plant.state.copy())
    return states


def test_kinematic_plant_is_the_models_integrate() -> None:
    model = DiffDrive(1.0, 2.0)
    start = np.array([1.0, 2.0, 0.3])
    plant = KinematicPlant(model, start)
    assert np.array_equal(plant.measured_velocity(), np.zeros(2))
    state = start
    for command in ([0.5, 0.2], [1.5, -3.0], [0.0, 1.0]):
        c = np.array(command)
        plant.step(c, DT)
        state = model.integrate(state, c, DT)
        assert np.array_equal(plant.state, state)
        assert np.array_equal(plant.measured_velocity(), c)       # the command it applied, as told
        assert np.array_equal(plant.velocity(), model.velocity(state, c))
        pose, twist = plant.odometry()
        assert np.array_equal(pose, state) and np.array_equal(twist, c)
    plant.step(None, DT)   # no new command: the last holds
    assert np.array_equal(plant.state, model.integrate(state, np.array([0.0, 1.0]), DT))


def test_make_plant() -> None:
    assert isinstance(make_plant('point_mass', PointMass(), np.zeros(2)), KinematicPlant)
    assert isinstance(make_plant('diff_drive', DiffDrive(), np.zeros(3), preset('nominal')), PhysicsPlant)
    with pytest.raises(ParameterError, match='only for model diff_drive, got point_mass'):
        make_plant('point_mass', PointMass(), np.zeros(2), preset('nominal'))


def test_same_inputs_same_trajectory() -> None:
    dynamics = replace(preset('slippery'), encoder_noise=0.002)
    commands = [(1.0, 0.5), (0.3, -1.5), (0.0, 0.0)]
    runs = []
    for _ in range(2):
        plant = PhysicsPlant(dynamics, np.array([3.0, -1.0, 2.0]), odometry_generator(7, 1))
        states = _drive(plant, commands, 20)
        runs.append((np.array(states), plant.odometry()[0]))
    assert np.array_equal(runs[0][0], runs[1][0])
    assert np.array_equal(runs[0][1], runs[1][1])
    other = PhysicsPlant(dynamics, np.array([3.0, -1.0, 2.0]), odometry_generator(8, 1))
    _drive(other, commands, 20)
    assert np.array_equal(other.state, runs[0][0][-1])          # the noise is the odometry's, not the body's
    assert not np.array_equal(other.odometry()[0], runs[0][1])   # another seed, other readings


def test_starts_exactly_at_rest_where_told() -> None:
    plant = PhysicsPlant(preset('heavy'), np.array([5.0, 6.0, -2.5]))
    assert np.allclose(plant.state, [5.0, 6.0, -2.5], atol=1e-12)
    assert np.array_equal(plant.measured_velocity(), np.zeros(2))
    plant.step(np.zeros(2), 1.0)
    assert np.allclose(plant.state, [5.0, 6.0, -2.5], atol=1e-4)   # it stands


def test_slip_makes_odometry_drift_while_the_true_pose_is_right() -> None:
    """Hard acceleration and turns on the slippery floor: the wheels spin, the odometry counts what they turned.
    The true state is where the body is (its velocity integrates to it); the odometry is off by decimetres."""
    commands = [(1.2, 0.0), (1.2, 1.5), (0.0, 0.0), (1.2, -1.5), (0.0, 0.0)]
    errors = {}
    for name in ('nominal', 'slippery'):
        plant = PhysicsPlant(preset(name), np.array([0.0, 0.0, 0.0]))
        position, integrated = plant.state[:2].copy(), plant.state[:2].copy()
        for v, omega in commands:
            for _ in range(30):
                for _ in range(5):   # the true velocity, integrated at 100 Hz, follows the true pose
                    plant.step(np.array([v, omega]), DT / 5)
                    integrated += plant.velocity() * DT / 5
        position = plant.state[:2]
        assert np.hypot(*(integrated - position)) < 0.03
        errors[name] = float(np.hypot(*(plant.odometry()[0][:2] - position)))
    assert errors['nominal'] < 0.1
    assert errors['slippery'] > 0.25
    assert errors['slippery'] > 4.0 * errors['nominal']


def test_command_timeout_stops_the_base() -> None:
    """No command after one sent at t = 0: it drives on it for cmd_timeout, then ramps to a stop within its
    deceleration limit."""
    dynamics = preset('nominal')
    plant = PhysicsPlant(dynamics, np.zeros(3))
    for _ in range(20):
        plant.step(np.array([1.0, 0.0]), DT)   # 1 s at 1 m/s, the last command sent at 0.95 s
    last_sent = plant.time - DT
    speeds = []
    for _ in range(30):
        plant.step(None, DT)   # nothing new comes
        speeds.append((plant.time, plant.controller.twist[0], plant.body_twist()[0]))
    before = [s for t, s, _ in speeds if t <= last_sent + dynamics.cmd_timeout]
    assert before and min(before) == pytest.approx(1.0)
    assert speeds[-1][1] == 0.0 and abs(speeds[-1][2]) < 0.01
    stopped_at = next(t for t, s, _ in speeds if s == 0.0)
    assert stopped_at == pytest.approx(last_sent + dynamics.cmd_timeout + 1.0 / dynamics.max_acceleration, abs=0.06)
    # A command sent long ago is stale at once (the sender's time counts, not the arrival's).
    late = PhysicsPlant(dynamics, np.zeros(3), start_time=10.0)
    late.step(np.array([1.0, 0.0]), 1.0, sent=9.0)
    assert late.controller.twist[0] == 0.0


def test_controller_limits_and_wheel_setpoints() -> None:
    dynamics = replace(preset('nominal'), max_speed=0.8, max_angular_speed=1.0, max_acceleration=1.0,
                       max_angular_acceleration=2.0)
    controller = BaseController(dynamics)
    controller.take(np.array([5.0, -5.0]), 0.0)
    left, right = controller.update(0.0, 0.1)
    assert not controller.timed_out(0.0) and controller.timed_out(dynamics.cmd_timeout + 0.01)
    assert controller.twist.tolist() == pytest.approx([0.1, -0.2])   # ramps at 1 m/s^2 and 2 rad/s^2
    half = 0.5 * dynamics.wheel_separation * -0.2
    assert (left, right) == pytest.approx(((0.1 - half) / dynamics.wheel_radius, (0.1 + half) / dynamics.wheel_radius))
    for k in range(1, 30):
        controller.take(np.array([5.0, -5.0]), 0.1 * k)
        controller.update(0.1 * k, 0.1)
    assert controller.twist.tolist() == pytest.approx([0.8, -1.0])   # and holds its speed limits
    controller.take(np.array([np.nan, 0.0]), 3.0)
    controller.update(3.0, 0.1)
    assert controller.twist.tolist() == pytest.approx([0.7, -0.8])   # a non-finite command is a stop


def test_mujoco_is_imported_only_for_a_physics_plant() -> None:
    code = ('import sys; import fastep_core.dynamics, fastep_core.simulator, fastep_core.scenario; '
            'from fastep_core.scenario import load_scenario; from fastep_core.simulator import simulate; '
            'simulate(load_scenario("open_field"), algorithm="fastep_route"); '
            'assert "mujoco" not in sys.modules, "imported"; '
            'import numpy as np; from fastep_core.dynamics import PhysicsPlant, preset; '
            'PhysicsPlant(preset("nominal"), np.zeros(3)); assert "mujoco" in sys.modules')
    subprocess.run([sys.executable, '-c', code], check=True, timeout=300)
