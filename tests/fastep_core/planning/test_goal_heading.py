"""A goal's heading (issue "Control that never waits", item 5): a diff_drive robot turns to it at the goal."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from fastep_core.errors import ScenarioError
from fastep_core.planning.navigator import ROTATING
from fastep_core.scenario import parse_scenario, scenario_data
from fastep_core.simulator import Tick, simulate


def _data(goal: list[float], model: str = 'diff_drive') -> dict[str, object]:
    start = [2.0, 10.0, 0.0] if model == 'diff_drive' else [2.0, 10.0]
    return {'workspace': [0, 0, 20, 20], 'obstacles': [],
            'robots': [{'name': 'd1', 'model': model, 'start': start, 'goal': goal, 'radius': 0.3}]}


def test_a_diff_drive_goal_may_carry_a_heading_and_writes_back_with_it() -> None:
    scenario = parse_scenario(_data([15.0, 10.0, 1.5]))
    robot = scenario.robots[0]
    assert robot.goal == (15.0, 10.0) and robot.goal_heading == 1.5
    assert scenario_data(scenario)['robots'][0]['goal'] == [15.0, 10.0, 1.5]
    assert parse_scenario(_data([15.0, 10.0])).robots[0].goal_heading is None


@pytest.mark.parametrize('goal', [[15.0, 10.0, 1.5], [15.0, 10.0, float('nan')]])
def test_a_heading_is_refused_in_one_line_where_it_cannot_be(goal: list[float]) -> None:
    model = 'point_mass' if math.isfinite(goal[2]) else 'diff_drive'
    with pytest.raises(ScenarioError) as error:
        parse_scenario(_data(goal, model))
    assert '\n' not in str(error.value) and 'goal' in str(error.value)


@pytest.mark.parametrize('heading', [1.5, -2.8, 3.1])
def test_the_robot_ends_facing_the_goal_heading_after_turning_in_place(heading: float) -> None:
    scenario = parse_scenario(_data([15.0, 10.0, heading]))
    reasons: list[str] = []
    robot = simulate(scenario, 'fastep_route', 0, observer=lambda tick: reasons.append(tick.navigator.reason)).robots[0]
    assert robot.reached and not robot.collided
    x, y, theta = robot.trajectory[-1][1:]
    assert math.hypot(x - 15.0, y - 10.0) <= scenario.planner.goal_tolerance
    error = math.atan2(math.sin(heading - theta), math.cos(heading - theta))
    assert abs(error) <= scenario.planner.yaw_goal_tolerance
    assert ROTATING in reasons


def test_goal_heading_0_stops_where_the_robot_arrives() -> None:
    scenario = parse_scenario(_data([15.0, 10.0, 3.0]))
    scenario = replace(scenario, planner=scenario.planner.with_overrides({'goal_heading': 0}))
    ticks: list[Tick] = []
    robot = simulate(scenario, 'fastep_route', 0, observer=ticks.append).robots[0]
    assert robot.reached
    assert abs(robot.trajectory[-1][3]) < 1.0   # it arrived heading east and stayed so
    assert all(t.navigator.reason != ROTATING for t in ticks)


def test_the_turn_keeps_to_the_turn_rate_and_its_acceleration() -> None:
    scenario = parse_scenario(_data([15.0, 10.0, 3.0]))
    p = scenario.planner
    turns = []
    simulate(scenario, 'fastep_route', 0,
             observer=lambda tick: turns.append(float(tick.command[1])) if tick.navigator.reason == ROTATING else None)
    assert turns and max(abs(w) for w in turns) <= p.max_turn_rate + 1e-9
    steps = [abs(b - a) for a, b in zip(turns, turns[1:])]
    assert max(steps) <= p.max_turn_acceleration * p.dt + 1e-9
