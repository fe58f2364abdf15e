"""What the live graph refuses of a v2 scenario until it can run it (fastep-launch and fastep-map: one line, exit 2)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from fastep_core.scenario import load_scenario, parse_scenario
from fastep_ros import launch
from fastep_ros.limits import graph_problem

ROBOT = {'name': 'r1', 'model': 'point_mass', 'start': [5, 25], 'goal': [45, 25], 'radius': 0.5}


def world(obstacle: dict[str, object], robot: dict[str, object] = ROBOT) -> dict[str, object]:
    return {'workspace': [0, 0, 50, 50], 'obstacles': [{'circle': {'center': [25, 10], 'radius': 1}}, obstacle],
            'robots': [robot]}


@pytest.mark.parametrize('extra, fragment', [
    ({'motion': {'waypoints': [[25, 40]], 'speed': 0.5}}, 'obstacles[1] moves (motion)'),
    ({'known': False}, 'obstacles[1] is unknown (known: false)'),
    ({'position_sigma': 0.2}, 'obstacles[1] is misplaced (position_sigma)'),
])
def test_obstacles_the_graph_cannot_honour(extra: dict[str, object], fragment: str) -> None:
    problem = graph_problem(parse_scenario(world({'circle': {'center': [25, 40], 'radius': 1}, **extra})))
    assert problem.startswith(fragment) and 'use fastep-sim' in problem


def test_diff_drive_and_sensors() -> None:
    robot = {**ROBOT, 'model': 'diff_drive', 'start': [5, 25, 0.0]}
    scenario = parse_scenario(world({'circle': {'center': [25, 40], 'radius': 1}}, robot))
    assert graph_problem(scenario) == ''   # diff_drive runs on the graph (plant and planner)
    assert graph_problem(scenario, robots=False) == ''   # the map node publishes no robot
    sensing = parse_scenario(world({'circle': {'center': [25, 40], 'radius': 1}}, {**ROBOT, 'sensor': {}}))
    assert graph_problem(sensing) == ''
    assert graph_problem(load_scenario('table2_s2')) == ''


def test_fastep_launch_refuses_a_mover_before_starting_anything(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / 'movers.yaml'
    path.write_text(yaml.safe_dump(world({'circle': {'center': [25, 40], 'radius': 1},
                                          'motion': {'waypoints': [[25, 45]], 'speed': 0.5}})))
    assert launch.main([str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'obstacles[1] moves (motion)' in err


def test_the_map_node_refuses_a_mover_in_one_line(context: Any, tmp_path: Path) -> None:
    from rclpy.parameter import Parameter

    from fastep_ros.errors import StartupError
    from fastep_ros.map_server import MapNode
    path = tmp_path / 'movers.yaml'
    path.write_text(yaml.safe_dump(world({'circle': {'center': [25, 40], 'radius': 1}, 'known': False})))
    with pytest.raises(StartupError, match=r'obstacles\[1\] is unknown \(known: false\): moving, unknown'):
        MapNode(context=context, parameter_overrides=[Parameter('scenario', value=str(path))])
