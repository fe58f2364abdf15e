"""FAStep-Route drives as fast as the way allows (params.regulated_speed; FAStepRoute.speed_allowed)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from fastep_core.geometry import Circle, Segment
from fastep_core.planning.algorithms import make_navigator
from fastep_core.planning.navigators.fastep_route import FAStepRoute
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import RobotSpec, parse_scenario
from fastep_core.simulator import Tick, simulate
from fastep_core.world import World


def _open_field(model: str = 'point_mass', regulated: int = 1) -> object:
    start = [5.0, 10.0] if model == 'point_mass' else [5.0, 10.0, 0.0]
    scenario = parse_scenario({'workspace': [0, 0, 40, 20], 'obstacles': [],
                               'robots': [{'name': 'r1', 'model': model, 'start': start, 'goal': [35.0, 10.0],
                                           'radius': 0.3}]})
    return replace(scenario, planner=scenario.planner.with_overrides({'regulated_speed': regulated}))


@pytest.mark.parametrize('model', ['point_mass', 'diff_drive'])
def test_an_open_run_takes_about_the_time_of_the_distance_at_max_speed(model: str) -> None:
    fast = simulate(_open_field(model), 'fastep_route', 0).robots[0]
    paper = simulate(_open_field(model, regulated=0), 'fastep_route', 0).robots[0]
    assert fast.reached and paper.reached and fast.sim_time is not None and paper.sim_time is not None
    at_top_speed = 30.0 / PlannerParams().max_speed
    assert fast.sim_time <= 1.1 * at_top_speed           # braking to the goal costs about v / (2 a)
    assert paper.sim_time >= 1.3 * at_top_speed          # eq. 12: speed gain x distance near the goal


def test_the_robot_brakes_to_the_goal_within_max_acceleration_and_stops_there() -> None:
    scenario = _open_field()
    p = scenario.planner
    ticks: list[Tick] = []
    robot = simulate(scenario, 'fastep_route', 0, observer=ticks.append).robots[0]
    assert robot.reached
    speeds = np.array([math.hypot(*t.command) for t in ticks])
    left = np.array([35.0 - t.state[0] for t in ticks]) + np.array([math.hypot(*t.command) * p.dt for t in ticks])
    assert speeds.max() <= p.max_speed + 1e-9
    # Fast enough to stop at max_acceleration from where the command was given (a tick's travel of slack).
    assert (speeds <= np.sqrt(2.0 * p.max_acceleration * np.maximum(left, 0.0)) + p.max_acceleration * p.dt).all()
    assert all(t.state[0] <= 35.0 + p.goal_tolerance for t in ticks)   # never past the goal


def test_speed_allowed_slows_for_a_bend_ahead_and_a_tight_gap() -> None:
    p = PlannerParams()
    # A wall from the south with its end at y = 10: the route bends round (20, 10 + clearance).
    world = World.from_obstacles((0.0, 0.0, 40.0, 30.0), [Segment((20.0, 0.0), (20.0, 10.0))])
    spec = RobotSpec('r1', 'point_mass', (5.0, 5.0), (35.0, 5.0), 0.3)
    nav = make_navigator('fastep_route', spec, 0.3, world, p, np.random.default_rng(0))
    assert isinstance(nav, FAStepRoute)
    nav.set_goal((35.0, 5.0))
    nav.update(0.0, np.array([5.0, 5.0]), ())
    far = nav.speed_allowed(np.array([5.0, 5.0]), p.dt)
    assert far == pytest.approx(p.max_speed)
    vertex = nav.step_target()
    near = vertex + np.array([-0.3, -0.05])
    assert nav.speed_allowed(near, p.dt) < far   # the route turns sharply at the vertex aimed at
    # Within radius + clearance_margin of the wall's end: slower, however straight the way on.
    squeezed = np.array([19.7, 10.3])
    room = float(world.obstacles.clearance(squeezed)) - 0.3
    assert room < p.clearance_margin
    assert nav.speed_allowed(squeezed, p.dt) <= max(p.min_approach_speed, p.max_speed * room / p.clearance_margin)


def test_a_plan_aimed_past_the_goal_allows_nothing_past_it_and_a_robot_past_it_is_aimed_back() -> None:
    p = PlannerParams()
    world = World.from_obstacles((0.0, 0.0, 40.0, 20.0), [Circle((30.0, 18.0), 0.5)])
    spec = RobotSpec('r1', 'point_mass', (5.0, 10.0), (20.0, 10.0), 0.3)
    nav = make_navigator('fastep_route', spec, 0.3, world, p, np.random.default_rng(0))
    assert isinstance(nav, FAStepRoute)
    nav.set_goal((20.0, 10.0))
    command = nav.update(0.0, np.array([5.0, 10.0]), ())
    assert nav.target is not None and nav.target[0] > 20.0   # aimed beyond the goal: no slow-down before it
    assert command[0] > 0.0
    assert nav.speed_allowed(np.array([20.5, 10.0]), p.dt) == 0.0
    # ... and a robot that went past it all the same (a late control tick) is aimed back at it from there, not
    # held where it stands.
    back = nav.update(p.dt, np.array([20.4, 10.0]), ())
    assert nav.target is not None and nav.target[0] < 20.0
    assert back[0] < 0.0 and nav.speed_allowed(np.array([20.4, 10.0]), p.dt) > 0.0


def test_a_steered_robot_slowed_keeps_its_curvature() -> None:
    p = PlannerParams()
    world = World.from_obstacles((0.0, 0.0, 40.0, 20.0), [])
    spec = RobotSpec('r1', 'diff_drive', (5.0, 10.0, 0.0), (20.0, 10.0), 0.3)
    nav = make_navigator('fastep_route', spec, 0.3, world, p, np.random.default_rng(0))
    nav.set_goal((20.0, 10.0))
    nav.update(0.0, np.array([5.0, 10.0, 0.0]), ())
    law = nav.speed_law()
    assert law is not None
    near_goal = np.array([19.9, 10.0, 0.0])
    slowed = law.regulate(near_goal, np.array([1.0, 0.4]), p.dt)
    assert slowed[0] < 1.0 and slowed[1] / slowed[0] == pytest.approx(0.4)
