"""Tests for scenario format v2 (docs/scenarios.md): movers, unknown and misplaced obstacles, sensors, diff_drive.

Each bad file gives one ScenarioError line naming the key and the problem; fastep-sim turns it into exit 2.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
import yaml

from fastep_core.dynamic_world import Motion, ObstacleSpec
from fastep_core.errors import ScenarioError
from fastep_core.geometry import Circle, Segment
from fastep_core.scenario import load_scenario, parse_scenario
from fastep_core.sensing.laser import LaserSpec
from msg_tools import sim_cli


def v2() -> dict[str, Any]:
    """A valid v2 world: a mover, an unknown circle, a misplaced wall, a robot with a sensor."""
    return {
        'name': 'v2',
        'workspace': [0, 0, 50, 50],
        'obstacles': [
            {'circle': {'center': [20, 25], 'radius': 1.0},
             'motion': {'waypoints': [[30, 25], [30, 35]], 'speed': 0.4}},
            {'circle': {'center': [35, 12], 'radius': 2.0}, 'known': False},
            {'segment': {'start': [10, 30], 'end': [20, 30]}, 'position_sigma': 0.5},
            {'circle': {'center': [40, 40], 'radius': 2.0}},
        ],
        'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [5, 5], 'goal': [45, 25], 'radius': 0.35,
                    'sensor': {'range': 6.0, 'fov': 6.2832, 'beams': 360, 'noise': 0.01}}],
    }


def write(tmp_path: Path, data: Any) -> Path:
    path = tmp_path / 'x.yaml'
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False))
    return path


def message(tmp_path: Path, data: Any) -> str:
    with pytest.raises(ScenarioError) as info:
        load_scenario(write(tmp_path, data))
    text = str(info.value)
    assert '\n' not in text and text.startswith("scenario '")
    return text


def test_the_design_example_loads_with_every_key(tmp_path: Path) -> None:
    scenario = load_scenario(write(tmp_path, v2()))
    specs = scenario.obstacle_specs
    assert specs[0] == ObstacleSpec(Circle((20.0, 25.0), 1.0), Motion(((30.0, 25.0), (30.0, 35.0)), 0.4))
    assert specs[1].known is False and specs[1].still
    assert specs[2].position_sigma == 0.5 and isinstance(specs[2].shape, Segment)
    assert not scenario.is_static
    # The true world of still obstacles: every still one (known or not) at its true place; the mover apart.
    assert scenario.world.obstacle_list == (specs[1].shape, specs[2].shape, specs[3].shape)
    assert scenario.robots[0].sensor == LaserSpec(6.0, 2 * math.pi, 360, 0.01)   # 6.2832 is a full turn


def test_v1_files_keep_their_meaning() -> None:
    for name in ('table2_s2', 'case_study_2', 'application'):
        scenario = load_scenario(name)
        assert scenario.is_static
        assert tuple(o.shape for o in scenario.obstacle_specs) == scenario.world.obstacle_list
        assert all(r.sensor is None for r in scenario.robots)


def test_sensor_keys_are_optional_with_documented_defaults(tmp_path: Path) -> None:
    data = v2()
    data['robots'][0]['sensor'] = {}
    assert load_scenario(write(tmp_path, data)).robots[0].sensor == LaserSpec()
    data['robots'][0]['sensor'] = {'beams': 200, 'fov': 1.0}
    assert load_scenario(write(tmp_path, data)).robots[0].sensor == LaserSpec(beams=200, fov=1.0)


def test_diff_drive_parses_its_pose(tmp_path: Path) -> None:
    data = v2()
    data['robots'][0].update(model='diff_drive', start=[5, 5, 0.5])
    assert load_scenario(write(tmp_path, data)).robots[0].start == (5.0, 5.0, 0.5)


def test_a_mover_path_may_cross_a_start_and_may_stand_still(tmp_path: Path) -> None:
    data = v2()
    data['obstacles'][0] = {'circle': {'center': [5, 15], 'radius': 1.0},
                            'motion': {'waypoints': [[5, 0.5]], 'speed': 0.4}}   # runs over r1's start (5, 5)
    load_scenario(write(tmp_path, data))
    data['obstacles'][0]['motion'] = {'waypoints': [[5, 15]], 'speed': 1.0}   # a path of length 0
    load_scenario(write(tmp_path, data))


def mover(**changes: Any) -> dict[str, Any]:
    data = v2()
    data['obstacles'][0].update(changes)
    return data


BAD: list[tuple[dict[str, Any], str]] = [
    (mover(motion={'waypoints': [], 'speed': 0.4}), 'obstacles[0].motion.waypoints must be a non-empty list'),
    (mover(motion={'speed': 0.4}), "obstacles[0].motion: missing required key 'waypoints'"),
    (mover(motion={'waypoints': [[30, 25]], 'speed': 0}), 'obstacles[0].motion.speed must be > 0, got 0'),
    (mover(motion={'waypoints': [[30, 25]], 'speed': -1}), 'obstacles[0].motion.speed must be > 0, got -1'),
    (mover(motion={'waypoints': [[30, float('nan')]], 'speed': 1}),
     'obstacles[0].motion.waypoints[0][1] must be a finite number, got nan'),
    (mover(motion={'waypoints': [[30]], 'speed': 1}), 'obstacles[0].motion.waypoints[0] must be a list of 2 numbers'),
    (mover(motion={'waypoints': [[30, 25]], 'speed': 1, 'loop': True}),
     "obstacles[0].motion: unknown key 'loop' (allowed: waypoints, speed)"),
    (mover(motion=[[30, 25]]), 'obstacles[0].motion must be a mapping'),
    (mover(known='maybe'), "obstacles[0].known must be true or false, got 'maybe'"),
    (mover(known=1), 'obstacles[0].known must be true or false, got 1'),
    (mover(position_sigma=-0.5), 'obstacles[0].position_sigma must be >= 0, got -0.5'),
    (mover(position_sigma=float('inf')), 'obstacles[0].position_sigma must be a finite number, got inf'),
    # Issue "Faults", item 8: 1e300 loaded, and the robot failed at once with numpy overflow warnings.
    (mover(position_sigma=1e300), "obstacles[0].position_sigma must be at most the workspace's larger side (50 m), "
                                  'got 1e+300'),
    (mover(colour='red'), "obstacles[0]: unknown key 'colour'"),
    (mover(circle={'center': [5, 5.5], 'radius': 1.0}),
     "obstacles[0] (a mover) starts 0.5 m from robots[0] (r1)'s start"),
    (mover(motion={'waypoints': [[45, 25]], 'speed': 1}), "the mover passes 0 m from robots[0] (r1)'s goal"),
]


def sensing(**sensor: Any) -> dict[str, Any]:
    data = v2()
    data['robots'][0]['sensor'] = sensor
    return data


# Issue "Faults", item 3: these loaded, and the robot drove into an unknown circle its scans returned dead ahead.
BAD += [
    (sensing(fov=0.01, beams=100), "robots[0].sensor cannot see the robot's way: its beams span 0.01 rad around 0 "
                                   'rad; the way ahead needs at least -0.464 to 0.464 rad in view'),
    (sensing(fov=1e-12, beams=1), "robots[0].sensor cannot see the robot's way: its beams span 0 rad"),
    (sensing(fov=3.0, beams=2), "robots[0].sensor cannot see the robot's way: 2 beams 3 rad apart"),
    (sensing(fov=3.0, beams=100, mount=[0, 0, 3.0]), 'its beams span 3 rad around 3 rad'),
    (sensing(fov=6.2832, beams=30), '30 beams 0.209 rad apart: a robot of radius'),
]


@pytest.mark.parametrize('data, fragment', BAD, ids=[fragment[:40] for _, fragment in BAD])
def test_bad_v2_files_give_one_line_naming_the_key(tmp_path: Path, data: dict[str, Any], fragment: str) -> None:
    assert fragment in message(tmp_path, data)


def test_only_circles_move(tmp_path: Path) -> None:
    data = v2()
    data['obstacles'][2]['motion'] = {'waypoints': [[30, 25]], 'speed': 1}
    assert 'obstacles[2].motion: only circles move, this obstacle is a segment' in message(tmp_path, data)


def test_two_shapes_in_one_entry(tmp_path: Path) -> None:
    data = v2()
    data['obstacles'][3]['segment'] = {'start': [1, 1], 'end': [2, 2]}
    assert 'obstacles[3] must have exactly one key (circle, segment)' in message(tmp_path, data)


def sensor(**keys: Any) -> dict[str, Any]:
    data = v2()
    data['robots'][0]['sensor'] = keys
    return data


BAD_SENSORS: list[tuple[dict[str, Any], str]] = [
    (sensor(fov=0), 'robots[0].sensor.fov must be in (0, 2 pi] radians'),
    (sensor(fov=7), 'robots[0].sensor.fov must be in (0, 2 pi] radians'),
    (sensor(range=0), 'robots[0].sensor.range must be > 0, got 0'),
    (sensor(beams=0), 'robots[0].sensor.beams must be in [1, 10000], got 0'),
    (sensor(beams=10 ** 6), 'robots[0].sensor.beams must be in [1, 10000], got 1000000'),
    (sensor(beams=36.5), 'robots[0].sensor.beams must be a whole number in [1, 10000], got 36.5'),
    (sensor(beams=True), 'robots[0].sensor.beams must be a whole number in [1, 10000], got True'),
    (sensor(beams='360'), "robots[0].sensor.beams must be a finite number, got '360' (text, not a number"),
    (sensor(noise=-0.01), 'robots[0].sensor.noise must be >= 0, got -0.01'),
    (sensor(rate=10), "robots[0].sensor: unknown key 'rate' (allowed: range, fov, beams, noise, mount)"),
]


@pytest.mark.parametrize('data, fragment', BAD_SENSORS, ids=[fragment[:40] for _, fragment in BAD_SENSORS])
def test_bad_sensors(tmp_path: Path, data: dict[str, Any], fragment: str) -> None:
    assert fragment in message(tmp_path, data)


def test_bad_diff_drive_start(tmp_path: Path) -> None:
    data = v2()
    data['robots'][0].update(model='diff_drive', start=[5, 5])
    assert 'robots[0].start must be a list of 3 numbers [x, y, theta]' in message(tmp_path, data)
    data['robots'][0].update(model='unicycle')
    assert 'robots[0].model must be one of point_mass, tractor_trailer, diff_drive' in message(tmp_path, data)


def test_unknown_obstacles_still_keep_starts_free(tmp_path: Path) -> None:
    data = v2()
    data['obstacles'][1] = {'circle': {'center': [5, 6], 'radius': 2.0}, 'known': False}
    assert 'robots[0] (r1): start (5, 5) is occupied' in message(tmp_path, data)


def test_fastep_sim_exits_2_with_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert sim_cli.main([str(write(tmp_path, mover(motion={'waypoints': [[30, 25]], 'speed': 0})))]) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'obstacles[0].motion.speed must be > 0' in err


def test_fastep_sim_runs_a_diff_drive(tmp_path: Path) -> None:
    """Issue 14 item 1: fastep-sim used to refuse diff_drive (exit 2, 'no kinematic model yet'); it runs it now,
    with trajectory rows [t, x, y, theta]."""
    data = v2()
    data['robots'][0].update(model='diff_drive', start=[5, 5, 3.0])
    data['robots'][0].pop('sensor')
    data['obstacles'] = data['obstacles'][3:]
    out = tmp_path / 'out.json'
    assert sim_cli.main([str(write(tmp_path, data)), '--algorithm', 'fastep_route', '--json', str(out)]) == 0
    robot = json.loads(out.read_text())['runs'][0]['robots'][0]
    assert robot['reached'] and not robot['collided'] and robot['model'] == 'diff_drive'
    rows = robot['trajectory']
    assert {len(row) for row in rows} == {4} and rows[0] == [0.0, 5.0, 5.0, 3.0]
    assert all(-math.pi < row[3] <= math.pi for row in rows)


def test_parse_scenario_accepts_v2_mappings() -> None:
    assert len(parse_scenario(v2()).obstacle_specs) == 4


def test_a_path_too_long_to_measure(tmp_path: Path) -> None:
    data = mover(motion={'waypoints': [[1e308, 25], [-1e308, 25]], 'speed': 1})
    assert 'obstacles[0].motion.waypoints: the path is too long to measure' in message(tmp_path, data)


def test_fastep_sim_refuses_to_record_a_v2_world(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert sim_cli.main([str(write(tmp_path, v2())), '--mcap', str(tmp_path / 'x.mcap')]) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and '--mcap: obstacles[0] moves (motion)' in err


def test_scenario_data_is_what_parse_scenario_reads_back_for_every_builtin_and_v2_family() -> None:
    from fastep_core.experiments.random_worlds import random_family_data
    from fastep_core.scenario import builtin_names, load_scenario, scenario_data
    scenarios = [load_scenario(name) for name in builtin_names()]
    scenarios += [parse_scenario(random_family_data(family, 1000001))
                  for family in ('dynamic_mix', 'misplaced_obstacles', 'tractor_trailer', 'diff_drive_robots')]
    for scenario in scenarios:
        back = parse_scenario(scenario_data(scenario))
        assert (back.name, back.world.workspace, back.robots, back.planner, back.obstacle_specs) == \
            (scenario.name, scenario.world.workspace, scenario.robots, scenario.planner, scenario.obstacle_specs)
