"""The algorithm registry (planning/algorithms.py) and what robot models say they can do."""

from __future__ import annotations

import numpy as np
import pytest

from fastep_core.errors import FastepError, ParameterError
from fastep_core.kinematics import PointMass, TractorTrailer
from fastep_core.planning import ALGORITHMS, PlannerParams, make_navigator
from fastep_core.planning.algorithms import NAVIGATORS, algorithm_name
from fastep_core.planning.recovery.manoeuvre_driver import ManoeuvreDriver
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

WORLD = World.from_obstacles([0, 0, 50, 50], [])
POINT = RobotSpec('r1', 'point_mass', (5.0, 5.0), (45.0, 45.0), 0.5)
TRACTOR = RobotSpec('r2', 'tractor_trailer', (5.0, 5.0, 0.0, 0.0), (45.0, 45.0), 0.5)


@pytest.mark.parametrize('algorithm', ALGORITHMS)
def test_every_registered_algorithm_builds_a_navigator_named_after_it(algorithm):
    nav = make_navigator(algorithm, POINT, 0.5, WORLD, PlannerParams(), 0)
    assert type(nav) is NAVIGATORS[algorithm] and nav.method == algorithm
    assert algorithm_name(algorithm) != algorithm   # a display name of its own (FAStep-Kinematic, FAStep-Route ...)


@pytest.mark.parametrize('algorithm', ALGORITHMS)
def test_a_navigator_without_a_goal_has_no_speed_law_and_a_plan_of_it_says_so(algorithm):
    """An idle planner node's planning pass (on wall time) asks before any goal: FAStep-Route raised there."""
    from fastep_core.planning.control import Plan
    nav = make_navigator(algorithm, POINT, 0.5, WORLD, PlannerParams(), 0)
    assert nav.speed_law() is None
    assert Plan.of(nav, 0.0, np.zeros(2), []).speed is None


def test_an_unknown_algorithm_or_model_is_a_one_line_fastep_error():
    with pytest.raises(ParameterError, match='unknown algorithm .nope.; choose one of fastep, fastep_paper, aco'):
        make_navigator('nope', POINT, 0.5, WORLD, PlannerParams())
    with pytest.raises(FastepError, match='unknown robot model'):
        make_navigator('fastep', RobotSpec('r3', 'hovercraft', (5.0, 5.0), (9.0, 9.0), 0.5), 0.5, WORLD,
                       PlannerParams())


def test_models_say_what_they_can_do():
    assert PointMass.holonomic and PointMass.turns_in_place and not PointMass.trailer
    assert not TractorTrailer.holonomic and not TractorTrailer.turns_in_place and TractorTrailer.trailer
    assert TractorTrailer.reverses and 1.2 < TractorTrailer.max_steer < 1.23   # 70 degrees


def test_only_a_robot_that_cannot_turn_in_place_manoeuvres():
    assert make_navigator('fastep', POINT, 0.5, WORLD, PlannerParams(), 0).manoeuvring is None
    tractor = make_navigator('fastep', TRACTOR, 0.5, WORLD, PlannerParams(), 0)
    assert isinstance(tractor.manoeuvring, ManoeuvreDriver) and tractor.manoeuvres == 0
    with pytest.raises(ParameterError, match='no manoeuvre search for a PointMass'):
        ManoeuvreDriver(PointMass(), 0.5, PlannerParams())
