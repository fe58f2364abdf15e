"""Each preset does what its name says, measured on the physics plant: braking distance from 1 m/s, the
acceleration it reaches, and (slippery) the wheels' slip."""

from __future__ import annotations

import numpy as np
import pytest

from fastep_core.dynamics import PhysicsPlant, preset

DT = 0.05


def _cruise(name: str, speed: float = 1.0) -> tuple[PhysicsPlant, float]:
    """The base of `name` driven at `speed` until steady; returns it and how long 0.9 x speed took (s)."""
    plant = PhysicsPlant(preset(name), np.array([0.0, 0.0, 0.0]))
    reached = None
    for _ in range(100):
        plant.step(np.array([speed, 0.0]), DT)
        if reached is None and plant.body_twist()[0] >= 0.9 * speed:
            reached = plant.time
    assert reached is not None
    assert plant.body_twist()[0] == pytest.approx(speed, abs=0.01)
    return plant, reached


def _braking_distance(plant: PhysicsPlant) -> float:
    start = plant.state[0]
    for _ in range(100):
        plant.step(np.array([0.0, 0.0]), DT)
    assert abs(plant.body_twist()[0]) < 1e-3
    return float(plant.state[0] - start)


# name: (seconds to 0.9 m/s, braking distance from 1 m/s (m)), as measured (tolerance 0.06 s, 6 %). The ideal:
# 2.5 m/s^2 is 0.36 s and 0.2 m; 0.8 m/s^2 is 1.125 s and 0.625 m; 0.5 m/s^2 is 1.8 s and 1 m. limited_controller
# stops in 0.93 m: the body ends 7 cm short of what its wheels turned over the 2 s ramp (odometry: 1.0 m).
EXPECTED = {'nominal': (0.40, 0.195), 'heavy': (1.15, 0.636), 'limited_controller': (1.75, 0.93)}


@pytest.mark.parametrize('name', sorted(EXPECTED))
def test_acceleration_and_braking(name: str) -> None:
    rise, distance = EXPECTED[name]
    plant, reached = _cruise(name)
    assert reached == pytest.approx(rise, abs=0.06)
    assert _braking_distance(plant) == pytest.approx(distance, rel=0.06)


def test_heavy_brakes_at_its_motors_limit_not_the_controllers() -> None:
    """heavy's controller asks for 2.5 m/s^2 like nominal's; its motors give ~0.8."""
    dynamics = preset('heavy')
    assert dynamics.max_acceleration == preset('nominal').max_acceleration
    assert dynamics.motor_acceleration == pytest.approx(0.8)
    plant, _ = _cruise('heavy')
    distance = _braking_distance(plant)
    assert 0.55 < distance < 0.7
    assert 1.0 / (2.0 * distance) == pytest.approx(0.8, rel=0.1)   # the deceleration it achieved


def test_slippery_slides_where_nominal_grips() -> None:
    """On friction 0.3 the grip gives less than the controller asks: the body slides on after its wheels stop
    (it brakes longer than nominal) and its odometry, which counts the wheels, says it went less far."""
    assert preset('slippery').grip_acceleration < preset('slippery').max_acceleration
    assert preset('nominal').grip_acceleration > preset('nominal').max_acceleration
    results = {}
    for name in ('nominal', 'slippery'):
        plant, _ = _cruise(name)
        odometry_start = plant.odometry()[0][0]
        start = plant.state[0]
        distance = _braking_distance(plant)
        results[name] = distance, plant.odometry()[0][0] - odometry_start, plant.state[0] - start
    nominal, slippery = results['nominal'], results['slippery']
    assert slippery[0] > 1.5 * nominal[0]
    assert abs(nominal[1] - nominal[2]) < 0.01            # nominal's odometry is right within 1 cm
    assert slippery[2] - slippery[1] > 0.1                # slippery's slid > 10 cm its wheels did not count
