"""Trap escape and 'no valid path': greedy steps settle inside a U; the exact path leads out."""

import json
import math

import numpy as np
import pytest

from fastep_core.experiments.random_worlds import u_trap
from fastep_core.planning import Mode
from fastep_core.scenario import parse_scenario
from fastep_core.simulator import simulate
from msg_tools.sim_cli import main as sim_main


def u_scenario(model='point_mass', trap_timeout=None, width=6.0, depth=4.0):
    robot = {'name': 'r1', 'model': model, 'start': [5, 15], 'goal': [35, 15], 'radius': 0.5}
    if model == 'tractor_trailer':
        robot.update(start=[5, 15, 0.0, 0.0], radius=0.6, length=1.0, trailer_length=1.0, width=0.5)
    data = {'name': 'u', 'workspace': [0, 0, 40, 30], 'obstacles': u_trap((20, 15), width, depth, np.pi),
            'robots': [robot]}
    if trap_timeout is not None:
        data['planner'] = {'trap_timeout': trap_timeout}
    return parse_scenario(data)


def test_u_trap_geometry_opens_towards_facing():
    walls = [sorted([tuple(w['segment']['start']), tuple(w['segment']['end'])])
             for w in u_trap((20, 15), 6.0, 4.0, np.pi)]   # open towards -x: back wall at x = 22
    assert sorted(walls) == [[(18.0, 12.0), (22.0, 12.0)], [(18.0, 18.0), (22.0, 18.0)], [(22.0, 12.0), (22.0, 18.0)]]


@pytest.mark.parametrize('algorithm', ['fastep', 'aco'])
def test_without_escape_the_u_trap_holds_the_robot(algorithm):
    robot = simulate(u_scenario(trap_timeout=0), algorithm, 0).robots[0]
    assert not robot.reached and 'failed to make progress' in robot.status and robot.escapes == 0


@pytest.mark.parametrize('algorithm', ['fastep', 'aco'])
def test_escape_leads_out_of_the_u_trap_without_touching_it(algorithm):
    robot = simulate(u_scenario(), algorithm, 0).robots[0]
    assert robot.reached and not robot.collided and robot.min_clearance > 0.0
    assert robot.escapes == 1
    # It went round the trap: the trajectory passes beyond one of the side walls (|y - 15| > 3).
    assert max(abs(row[2] - 15.0) for row in robot.trajectory) > 3.0


@pytest.mark.parametrize('width', [6.0, 3.5])
def test_tractor_trailer_manoeuvres_out_of_the_u_trap_without_folding_its_trailer(width):
    robot = simulate(u_scenario('tractor_trailer', width=width, depth=3.0), 'fastep', 0).robots[0]
    assert robot.reached and not robot.collided and robot.escapes == 1 and robot.manoeuvres >= 1
    hitch = [abs(math.remainder(row[4] - row[3], 2 * math.pi)) for row in robot.trajectory]
    assert max(hitch) < 1.0 + 1e-6   # the manoeuvre's limit; past pi/2 the steering law folds it further


def test_escape_hands_back_to_fastep_before_the_goal():
    modes = []
    simulate(u_scenario(), 'fastep', 0,
             observer=lambda tick: modes.append((tick.navigator.reason, tick.navigator.mode)))
    reasons = [r for r, _ in modes]
    first_escape = next(i for i, r in enumerate(reasons) if r.startswith('escaping'))
    last_escape = max(i for i, r in enumerate(reasons) if r.startswith('escaping'))
    assert 'way is clear' in reasons[last_escape:]   # kinematic again after the escape
    assert 'way is clear' in reasons[:first_escape]
    assert all(mode is not Mode.FAILED for _, mode in modes)


def walled_goal_data():
    a, b = 29.0, 31.0   # a closed square around the goal
    walls = [{'segment': {'start': p, 'end': q}} for p, q in
             (([a, a], [b, a]), ([b, a], [b, b]), ([b, b], [a, b]), ([a, b], [a, a]))]
    return {'name': 'walled', 'workspace': [0, 0, 40, 40], 'obstacles': walls,
            'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [5, 5], 'goal': [30, 30], 'radius': 0.5}]}


def test_goal_nothing_reaches_fails_at_once_with_no_valid_path():
    robot = simulate(parse_scenario(walled_goal_data()), 'fastep', 0).robots[0]
    assert not robot.reached and robot.status.startswith('failed: no valid path')
    assert robot.path_length == 0.0 and robot.activations == 0


def test_fastep_sim_json_reports_no_valid_path(tmp_path):
    import yaml
    path = tmp_path / 'walled.yaml'
    path.write_text(yaml.safe_dump(walled_goal_data()))
    assert sim_main([str(path), '--json', str(tmp_path / 'run.json')]) == 0
    robot = json.loads((tmp_path / 'run.json').read_text())['runs'][0]['robots'][0]
    assert robot['reached'] is False and robot['status'].startswith('failed: no valid path')
    assert robot['escapes'] == 0


def test_gap_only_the_radius_fits_through_is_still_a_path():
    # A wall across the map with a 1.2 m gap: wider than the robot (1.0 m), narrower than 2 x (r + margin).
    walls = [{'segment': {'start': [20, 0], 'end': [20, 14.4]}}, {'segment': {'start': [20, 15.6], 'end': [20, 30]}}]
    data = {'name': 'gap', 'workspace': [0, 0, 40, 30], 'obstacles': walls,
            'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [5, 15], 'goal': [35, 15], 'radius': 0.5}]}
    robot = simulate(parse_scenario(data), 'fastep', 0).robots[0]
    assert robot.reached and not robot.collided


def test_a_robot_a_little_inside_its_radius_has_a_path_that_backs_out_first():
    """A new scan put an obstacle 1 cm nearer than the radius: the path starts where the robot is and leaves the
    obstacle's reach at once; 10 cm inside (more than BACK_OUT) is no robot's way out."""
    from fastep_core.geometry import Circle
    from fastep_core.planning.params import PlannerParams
    from fastep_core.planning.shortest_path.exact_path import BACK_OUT, exact_path
    from fastep_core.world import World
    world = World.from_obstacles([0, 0, 20, 20], [Circle((5.99, 5.0), 0.5)])
    radius, position, goal = 0.5, np.array([5.0, 5.0]), np.array([15.0, 5.0])
    assert 0.0 < radius - float(world.obstacles.clearance(position[None])[0]) < BACK_OUT
    path = exact_path(world, position, goal, radius, PlannerParams())
    assert path is not None
    np.testing.assert_allclose(path.points[0], position)
    assert float(world.obstacles.clearance(path.points[1:2])[0]) >= radius
    deep = World.from_obstacles([0, 0, 20, 20], [Circle((5.9, 5.0), 0.5)])   # 0.1 m inside
    assert exact_path(deep, position, goal, radius, PlannerParams()) is None
