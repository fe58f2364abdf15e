"""min_approach_speed: a robot reaches each waypoint and its goal in bounded time (issue 14, item 7).

Eq. 12 / 13 alone set the speed to gain x distance: near an obstacle, where the swarm's waypoints are at most
step_radius (2 m) away, a robot crawled at 0.01-0.17 m/s, 35 s for 2 m. The controllers now drive at least
min_approach_speed (kinematics/point_mass.py proves the bound); Table 2 keeps the paper's gains (0).
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from fastep_core.experiments.batches import TABLE2, cached_scenario
from fastep_core.kinematics import PointMassController, TractorTrailerController
from fastep_core.planning.algorithms import make_robot
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import parse_scenario
from fastep_core.simulator import simulate

DEFAULT = PlannerParams()


def _short_hop(planner: dict[str, Any], goal: list[float]) -> Any:
    """A point mass next to a circle, its goal a short hop away (the circle is beside the run, within sensing)."""
    return parse_scenario({
        'name': 'hop', 'workspace': [0, 0, 20, 20],
        'obstacles': [{'circle': {'center': [6.0, 6.6], 'radius': 0.8}}],
        'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [5.0, 5.0], 'goal': goal, 'radius': 0.5}],
        'planner': planner})


def test_the_default_is_a_minimum_speed_below_the_speed_limit() -> None:
    assert 0.0 < DEFAULT.min_approach_speed <= DEFAULT.max_speed


@pytest.mark.parametrize('algorithm', ['fastep', 'fastep_paper', 'fastep_route', 'aco', 'optimal'])
def test_a_two_metre_hop_next_to_an_obstacle_takes_bounded_time(algorithm: str) -> None:
    """2 m at min_approach_speed or faster, to within goal_tolerance: (2 - 0.1) / m + one tick, and a tick to stop
    there (arrival is stopped at the goal). Before: 30 s."""
    run = simulate(_short_hop({}, [7.0, 5.0]), algorithm, 0).robots[0]
    assert run.reached and not run.collided
    assert run.sim_time <= (2.0 - DEFAULT.goal_tolerance) / DEFAULT.min_approach_speed + 2 * DEFAULT.dt + 1e-9
    # FAStep-Route's regulated speed (the default) is no eq. 12 approach: the paper's gains alone without it.
    paper = simulate(_short_hop({'min_approach_speed': 0.0, 'regulated_speed': 0}, [7.0, 5.0]), algorithm, 0).robots[0]
    assert paper.sim_time == pytest.approx(math.log(2.0 / DEFAULT.goal_tolerance) / DEFAULT.alpha1, abs=0.1)


def test_make_robot_wires_min_approach_speed_into_both_controllers() -> None:
    class Spec:
        length, trailer_length, hitch_offset = 1.0, 1.0, 0.0

        def __init__(self, model: str) -> None:
            self.model = model

    params = DEFAULT.with_overrides({'min_approach_speed': 0.4})
    for model in ('point_mass', 'tractor_trailer'):
        _, controller = make_robot(Spec(model), params)
        assert isinstance(controller, (PointMassController, TractorTrailerController))
        assert controller.min_speed == 0.4


def test_table2_runs_the_papers_gains() -> None:
    """The paper's Table 2 is reproduced with eq. 12 / 13 alone: its scenarios set min_approach_speed 0."""
    for source in TABLE2:
        assert cached_scenario(source).planner.min_approach_speed == 0.0
