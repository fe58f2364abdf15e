"""A robot's `footprint` in scenario format v2 (docs/scenarios.md): its rules, its radius, starts and goals checked
with it, one error line per problem, and scenario_data keeping it."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest
import yaml

from fastep_core.errors import ScenarioError
from fastep_core.footprint import Footprint
from fastep_core.scenario import load_scenario, parse_scenario, scenario_data

JACKAL = [[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]]
CORNER = math.hypot(0.254, 0.215)


def world(**robot: Any) -> dict[str, Any]:
    base: dict[str, Any] = {'name': 'r1', 'model': 'diff_drive', 'start': [2.0, 2.0, 0.0], 'goal': [8.0, 2.0],
                            'footprint': JACKAL}
    base.update(robot)
    return {'workspace': [0, 0, 10, 10], 'obstacles': [{'circle': {'center': [5.0, 5.0], 'radius': 0.5}}],
            'robots': [{k: v for k, v in base.items() if v is not None}]}


def message(tmp_path: Path, data: dict[str, Any]) -> str:
    path = tmp_path / 'x.yaml'
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    text = str(info.value)
    assert '\n' not in text and text.startswith(f"scenario '{path}': ")
    return text


def test_a_footprint_without_a_radius_takes_its_circumscribed_radius() -> None:
    robot = parse_scenario(world()).robots[0]
    assert robot.footprint == Footprint.parse(JACKAL)
    assert robot.radius == pytest.approx(CORNER)


def test_a_radius_that_covers_the_footprint_is_kept() -> None:
    assert parse_scenario(world(radius=0.4)).robots[0].radius == 0.4


def test_a_clockwise_footprint_loads_counter_clockwise() -> None:
    robot = parse_scenario(world(footprint=JACKAL[::-1])).robots[0]
    assert robot.footprint == Footprint.parse(JACKAL[::-1]) and robot.footprint is not None
    x, y = robot.footprint.vertices[:, 0], robot.footprint.vertices[:, 1]
    assert float((x * (list(y[1:]) + [y[0]])).sum() - (y * (list(x[1:]) + [x[0]])).sum()) > 0.0


@pytest.mark.parametrize('robot, words', [
    ({'radius': 0.22}, "robots[0].radius 0.22 m is below the footprint's circumscribed radius 0.332778 m"),
    ({'footprint': JACKAL[:2]}, 'robots[0].footprint needs at least 3 vertices, got 2'),
    ({'footprint': [[0.3, 0.2], [-0.3, 0.2], [-0.3, '.nan']]}, 'robots[0].footprint[2][1] must be a finite number'),
    ({'footprint': [[1.0, 1.0], [2.0, 1.0], [2.0, 2.0]]}, 'robots[0].footprint must hold base_link (0, 0) inside it'),
    ({'footprint': [[-0.3, -0.3], [0.3, 0.3], [0.3, -0.3], [-0.3, 0.3]]}, 'robots[0].footprint intersects itself'),
    ({'footprint': [[-0.3, 0.0], [0.0, 0.0], [0.3, 0.0]]}, 'robots[0].footprint has zero area'),
    ({'footprint': [[0.3, 0.2], [-0.3, 0.2], [-0.3]]}, 'robots[0].footprint[2] must be a list of 2 numbers'),
    ({'footprint': '[[0.3, 0.2], [-0.3, 0.2], [-0.3, -0.2]]'}, 'robots[0].footprint must be a list of [x, y] vertices'),
    ({'model': 'point_mass', 'start': [2.0, 2.0]}, 'robots[0].footprint is only valid for model diff_drive'),
    ({'footprint': None, 'radius': None}, "robots[0]: missing required key 'radius'"),
    ({'start': [5.0, 4.3, 1.0], 'radius': 0.4}, 'robots[0] (r1): start (5, 4.3) is occupied: its footprint at '
                                                'heading 1 overlaps an obstacle by'),
    ({'goal': [5.0, 4.3, 0.0]}, 'robots[0] (r1): goal (5, 4.3) is occupied: its footprint at heading 0 overlaps'),
])
def test_a_bad_footprint_is_one_line(tmp_path: Path, robot: dict[str, Any], words: str) -> None:
    assert words in message(tmp_path, world(**robot))


def test_a_start_checked_by_its_box_not_its_circle() -> None:
    # Beside the cylinder with the box's short side toward it: closer than the circumscribed circle, clear of the
    # box. Turned a quarter, its long side reaches into the cylinder.
    robot = {'start': [5.0, 5.0 - 0.5 - 0.215 - 0.02, 0.0], 'goal': [8.0, 2.0]}
    assert parse_scenario(world(**robot)).robots[0].radius == pytest.approx(CORNER)
    with pytest.raises(ScenarioError, match='its footprint at heading 1.5708 overlaps an obstacle'):
        parse_scenario(world(start=[5.0, 5.0 - 0.5 - 0.215 - 0.02, math.pi / 2]))


def test_a_goal_without_a_heading_keeps_the_circle() -> None:
    with pytest.raises(ScenarioError, match='goal .* is occupied: 0.215 m from an obstacle, robot radius 0.332778 m'):
        parse_scenario(world(goal=[5.0, 5.0 - 0.5 - 0.215]))
    assert parse_scenario(world(goal=[5.0, 5.0 - 0.5 - 0.22, 0.0])).robots[0].goal_heading == 0.0


def test_scenario_data_keeps_the_footprint() -> None:
    for data in (world(), world(radius=0.5), world(footprint=JACKAL[::-1])):
        scenario = parse_scenario(data)
        back = parse_scenario(scenario_data(scenario))
        footprint = scenario.robots[0].footprint
        assert footprint is not None and back == scenario and back.robots[0].footprint == footprint
        assert scenario_data(scenario)['robots'][0]['footprint'] == footprint.to_list()


def test_a_circle_robot_has_no_footprint_and_writes_none() -> None:
    scenario = parse_scenario(world(footprint=None, radius=0.3))
    assert scenario.robots[0].footprint is None and 'footprint' not in scenario_data(scenario)['robots'][0]
