"""A laser mounted off the robot's reference point (scenario v2 `sensor.mount`, LaserSpec.mount)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.errors import ScenarioError
from fastep_core.geometry import Circle
from fastep_core.scenario import parse_scenario, scenario_data
from fastep_core.sensing.laser import LaserSpec
from fastep_core.simulator import simulate


def _data(mount: list[float] | None, radius: float = 0.5) -> dict[str, object]:
    sensor: dict[str, object] = {'range': 8.0, 'fov': 4.71, 'beams': 360, 'noise': 0.01}
    if mount is not None:
        sensor['mount'] = mount
    return {'workspace': [0, 0, 24, 20],
            'obstacles': [{'circle': {'center': [12.0, 10.0], 'radius': 1.5}, 'known': False}],
            'robots': [{'name': 'r1', 'model': 'diff_drive', 'start': [3.0, 10.0, 0.0], 'goal': [21.0, 10.0],
                        'radius': radius, 'sensor': sensor}]}


def test_the_scanner_s_pose_is_its_mount_on_the_robot() -> None:
    spec = LaserSpec(mount=(0.25, 0.1, 0.5))
    x, y, heading = spec.pose_on((1.0, 2.0, math.pi / 2))
    assert (x, y, heading) == pytest.approx((0.9, 2.25, math.pi / 2 + 0.5))
    assert LaserSpec().pose_on((1.0, 2.0, 3.0)) == (1.0, 2.0, 3.0)


def test_a_mount_is_read_written_and_refused_off_the_robot_in_one_line() -> None:
    scenario = parse_scenario(_data([0.25, 0.0, 0.0]))
    sensor = scenario.robots[0].sensor
    assert sensor is not None and sensor.mount == (0.25, 0.0, 0.0)
    written = scenario_data(scenario)['robots'][0]['sensor']
    assert written['mount'] == [0.25, 0.0, 0.0]
    assert 'mount' not in scenario_data(parse_scenario(_data(None)))['robots'][0]['sensor']
    for bad in ([0.25, 0.0], [1.0, 0.0, 0.0], [0.1, float('nan'), 0.0]):
        with pytest.raises(ScenarioError) as error:
            parse_scenario(_data(bad))
        assert '\n' not in str(error.value) and 'mount' in str(error.value)


def test_a_robot_with_a_laser_ahead_of_its_centre_sees_the_obstacle_where_it_is() -> None:
    scenario = parse_scenario(_data([0.35, 0.0, 0.0]))
    run = simulate(scenario, 'fastep_route', 0)
    robot = run.robots[0]
    assert robot.reached and not robot.collided
    assert robot.belief is not None
    circles = [o for o in robot.belief.world.obstacle_list if isinstance(o, Circle)]
    nearest = min(circles, key=lambda c: math.hypot(c.center[0] - 12.0, c.center[1] - 10.0))
    assert math.hypot(nearest.center[0] - 12.0, nearest.center[1] - 10.0) < 0.1
    assert abs(nearest.radius - 1.5) < 0.1
    assert np.isfinite(robot.min_clearance)
