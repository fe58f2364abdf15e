"""A robot's `dynamics:` in a scenario (format v2, docs/scenarios.md): presets, overrides, one-line errors, the
writer's round trip; and fastep-sim driving a physics robot to its goal."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from fastep_core.dynamics import PRESETS, preset
from fastep_core.errors import ScenarioError
from fastep_core.scenario import parse_scenario, scenario_data
from fastep_core.simulator import simulate

ROBOT = {'name': 'd', 'model': 'diff_drive', 'start': [2, 10, 0], 'goal': [18, 12], 'radius': 0.35}
DATA = {'workspace': [0, 0, 20, 20], 'robots': [ROBOT]}


def _with(dynamics: Any, **robot: Any) -> dict[str, Any]:
    data = copy.deepcopy(DATA)
    data['robots'][0].update(robot, dynamics=dynamics)
    return data


def test_no_dynamics_is_kinematic() -> None:
    assert parse_scenario(copy.deepcopy(DATA)).robots[0].dynamics is None
    assert 'dynamics' not in scenario_data(parse_scenario(copy.deepcopy(DATA)))['robots'][0]


@pytest.mark.parametrize('name', sorted(PRESETS))
def test_a_preset_by_name(name: str) -> None:
    scenario = parse_scenario(_with(name))
    assert scenario.robots[0].dynamics == preset(name)
    assert scenario_data(scenario)['robots'][0]['dynamics'] == name
    assert parse_scenario(scenario_data(scenario)) == scenario


def test_overrides_and_round_trip() -> None:
    scenario = parse_scenario(_with({'preset': 'heavy', 'mass': 45, 'encoder_noise': 0.001}))
    dynamics = scenario.robots[0].dynamics
    assert dynamics is not None
    assert (dynamics.preset, dynamics.mass, dynamics.encoder_noise) == ('heavy', 45.0, 0.001)
    assert dynamics.max_wheel_torque == preset('heavy').max_wheel_torque
    assert scenario_data(scenario)['robots'][0]['dynamics'] == {'preset': 'heavy', 'mass': 45.0,
                                                                'encoder_noise': 0.001}
    assert parse_scenario(scenario_data(scenario)) == scenario
    assert parse_scenario(_with({})).robots[0].dynamics == preset('nominal')   # a mapping's preset: nominal


@pytest.mark.parametrize(('dynamics', 'robot', 'message'), [
    ('fast', {}, "robots[0].dynamics.preset must be one of nominal, heavy, limited_controller, slippery, got 'fast'"),
    ({'mass': -1}, {}, 'robots[0].dynamics.mass must be > 0, got -1'),
    ({'colour': 'red'}, {}, "robots[0].dynamics: unknown key 'colour' (allowed: preset, mass, "),
    ({'friction': 'high'}, {}, "robots[0].dynamics.friction must be a finite number, got 'high'"),
    ({'friction': True}, {}, 'robots[0].dynamics.friction must be a finite number, got True'),
    ({'encoder_noise': -0.1}, {}, 'robots[0].dynamics.encoder_noise must be in [0, 1], got -0.1'),
    ({'com_offset': 0.5}, {}, 'robots[0].dynamics.com_offset 0.5 m must be below caster_offset 0.3 m'),
    ({'control_rate': 300}, {}, 'robots[0].dynamics.control_rate 300 Hz must divide the physics rate 500 Hz'),
    ([1, 2], {}, 'robots[0].dynamics must be a preset name (nominal, heavy, limited_controller, slippery) or a '
                 'mapping of its fields, got [1, 2]'),
    ('heavy', {'model': 'point_mass', 'start': [2, 10]},
     'robots[0].dynamics is only valid for model diff_drive (a physics plant), not point_mass'),
])
def test_errors_are_one_line_naming_the_key(dynamics: Any, robot: dict[str, Any], message: str) -> None:
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(_with(dynamics, **robot), default_name='x.yaml')
    text = str(caught.value)
    assert '\n' not in text
    assert text.startswith(f"scenario 'x.yaml': {message}")


@pytest.mark.parametrize('name', ['nominal', 'heavy'])
def test_simulator_drives_a_physics_robot_to_its_goal(name: str) -> None:
    """Open floor: a physics base arrives; its trajectory is the true pose, which differs from the kinematic run
    (it lags and overshoots a little), and the same seed gives the same run."""
    kinematic = simulate(parse_scenario(copy.deepcopy(DATA)), algorithm='fastep_route', seed=0).robots[0]
    runs = [simulate(parse_scenario(_with(name)), algorithm='fastep_route', seed=0).robots[0] for _ in range(2)]
    robot = runs[0]
    assert robot.reached and not robot.collided, robot.status
    assert np.hypot(robot.trajectory[-1][1] - 18.0, robot.trajectory[-1][2] - 12.0) < 0.5
    assert robot.trajectory != kinematic.trajectory
    assert robot.sim_time is not None and kinematic.sim_time is not None and robot.sim_time > kinematic.sim_time
    assert runs[1].trajectory == robot.trajectory and runs[1].path_length == robot.path_length


def test_simulator_gives_the_planner_the_odometry_twist(monkeypatch: pytest.MonkeyPatch) -> None:
    """The navigator is told the plant's measured velocity before each tick's command: a heavy base's lags the
    commands it was sent."""
    from fastep_core.planning.navigator import Navigator

    told: list[tuple[np.ndarray, np.ndarray]] = []
    update = Navigator.update

    def spy(self: Navigator, t: float, state: Any, others: Any = (), velocity: Any = None) -> Any:
        command = update(self, t, state, others, velocity=velocity)
        told.append((np.array(velocity), np.array(command)))
        return command

    monkeypatch.setattr(Navigator, 'update', spy)
    data = _with('heavy')
    data['planner'] = {'max_sim_time': 3.0}
    simulate(parse_scenario(data), algorithm='fastep_route', seed=0)
    assert len(told) > 20
    gaps = [abs(float(told[k][0][0]) - float(told[k - 1][1][0])) for k in range(1, len(told))]
    assert max(gaps) > 0.05    # what the base did is not what it was told
