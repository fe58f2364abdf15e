"""The dense-clutter families (fastep_core/experiments/dense_clutter.py): BARN-shaped worlds for a Jackal-class base."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.experiments.dense_clutter import CELL, DENSE_FAMILIES, ROBOT_RADIUS, dense_clutter_data
from fastep_core.experiments.random_worlds import ALL_FAMILIES, FAMILIES, random_family_data, solvable
from fastep_core.scenario import parse_scenario
from fastep_core.simulator import simulate


def test_same_seed_same_world_and_the_families_are_listed_apart_from_the_default_table() -> None:
    assert dense_clutter_data(3) == dense_clutter_data(3) != dense_clutter_data(4)
    assert set(DENSE_FAMILIES) <= set(ALL_FAMILIES) and not set(DENSE_FAMILIES) & set(FAMILIES)


@pytest.mark.parametrize('seed', range(1_000_000, 1_000_004))
def test_a_world_is_a_cylinder_field_between_a_closed_start_box_and_a_goal_10_m_ahead(seed: int) -> None:
    data = random_family_data('dense_clutter_laser', seed)
    scenario = parse_scenario(data)
    assert solvable(scenario)
    (robot,) = scenario.robots
    assert robot.model == 'diff_drive' and robot.radius == ROBOT_RADIUS and scenario.planner.max_speed == 2.0
    assert robot.sensor is not None and robot.sensor.beams == 720
    assert robot.sensor.fov == pytest.approx(1.5 * math.pi, abs=1e-8)   # 270 degrees
    assert math.hypot(robot.goal[0] - robot.start[0], robot.goal[1] - robot.start[1]) == pytest.approx(10.0)
    cylinders = [o for o in data['obstacles'] if 'circle' in o]
    assert len(cylinders) > 50   # walls and pockets, not a few stray poles
    centres = np.array([o['circle']['center'] for o in cylinders])
    assert all(o['circle']['radius'] == CELL / 2.0 and o['known'] is False for o in cylinders)
    on_grid = centres / CELL - 0.5 - np.round(centres / CELL - 0.5)
    assert np.abs(on_grid[:, 0]).max() < 1e-6   # at cell centres
    walls = [o['segment'] for o in data['obstacles'] if 'segment' in o]
    behind = [w for w in walls if w['start'][1] == w['end'][1] == 0.0]
    sides = [w for w in walls if w['start'][0] == w['end'][0]]
    assert len(behind) == 1 and len(sides) == 2   # the start box: closed behind and on both sides
    assert all(o.get('known', True) for o in random_family_data('dense_clutter', seed)['obstacles'])


def test_fastep_route_crosses_a_laser_only_field_without_touching_a_cylinder() -> None:
    scenario = parse_scenario(random_family_data('dense_clutter_laser', 1_000_001))
    robot = simulate(scenario, 'fastep_route', 0).robots[0]
    assert robot.reached and not robot.collided


@pytest.mark.parametrize('seed', [1_000_000, 1_000_003])
def test_the_jackal_family_is_the_laser_familys_world_with_the_jackals_box(seed: int) -> None:
    from fastep_core.experiments.dense_clutter import JACKAL_FOOTPRINT
    from fastep_core.footprint import Footprint

    laser, jackal = random_family_data('dense_clutter_laser', seed), random_family_data('dense_clutter_jackal', seed)
    assert jackal['obstacles'] == laser['obstacles'] and jackal['workspace'] == laser['workspace']
    assert jackal['planner'] == laser['planner']
    (robot,) = parse_scenario(jackal).robots
    assert robot.footprint == Footprint.parse(JACKAL_FOOTPRINT)
    assert robot.radius == pytest.approx(math.hypot(0.254, 0.215))   # planned with the circumscribed circle
    assert robot.start == parse_scenario(laser).robots[0].start and robot.sensor is not None
