"""fastep-sim in a v2 world: movers move, planners see the map (known, misplaced) and known movers as moving
obstacles, and collisions are judged against the truth over time."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from fastep_core.dynamic_world import Motion, Movers
from fastep_core.geometry import Circle, Obstacles
from fastep_core.metrics import trajectory_margins
from fastep_core.scenario import load_scenario, parse_scenario
from fastep_core.simulator import simulate

# r1 drives (5, 25) -> (45, 25) and, alone, passes x = 25 at t = 20 s (fastep, every seed): a mover starting
# at (25, 17) northwards at 0.4 m/s is at (25, 25) then, head on.
CROSSING: dict[str, Any] = {
    'workspace': [0, 0, 50, 50],
    'obstacles': [{'circle': {'center': [25, 17], 'radius': 1.0},
                   'motion': {'waypoints': [[25, 45]], 'speed': 0.4}}],
    'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [5, 25], 'goal': [45, 25], 'radius': 0.5}],
}


def crossing(**changes: Any) -> dict[str, Any]:
    data = copy.deepcopy(CROSSING)
    data['obstacles'][0].update(changes)
    return data


@pytest.mark.parametrize('seed', [0, 1])
def test_a_known_mover_is_avoided_an_unknown_one_is_not(seed: int) -> None:
    """Known movers reach the planner as moving obstacles ('mover 0'); an unknown one is absent from what it is
    given (this robot has no sensor), so it runs the robot down: judged from the truth. The known one is let
    pass (planning/safety/yielding.py: the robot slows down for it) with more than the clearance margin to spare."""
    seen = simulate(parse_scenario(crossing()), 'fastep', seed).robots[0]
    assert seen.reached and not seen.collided and seen.min_clearance > 0.5
    unseen = simulate(parse_scenario(crossing(known=False)), 'fastep', seed).robots[0]
    assert unseen.reached and unseen.collided and unseen.min_clearance < -1.0


def test_an_unknown_still_obstacle_on_the_run_is_hit() -> None:
    data = copy.deepcopy(CROSSING)
    data['obstacles'] = [{'circle': {'center': [25, 25], 'radius': 2.0}, 'known': False}]
    robot = simulate(parse_scenario(data), 'fastep', 0).robots[0]
    assert robot.collided and robot.min_clearance < -1.0
    data['obstacles'][0]['known'] = True
    robot = simulate(parse_scenario(data), 'fastep', 0).robots[0]
    assert robot.reached and not robot.collided


def test_the_map_error_does_not_touch_the_swarms_draws() -> None:
    """A misplaced obstacle whose error is too small to move it (1e-300 m): the map is drawn from its own
    stream and the run is the one without position_sigma, bit for bit."""
    data = copy.deepcopy(CROSSING)
    data['obstacles'] = [{'circle': {'center': [25, 26], 'radius': 1.5}}, {'circle': {'center': [40, 40], 'radius': 2}}]
    plain = simulate(parse_scenario(data), 'fastep', 4).robots[0]
    data['obstacles'][1]['position_sigma'] = 1e-300
    misplaced = simulate(parse_scenario(data), 'fastep', 4).robots[0]
    assert plain.activations > 0 and misplaced.trajectory == plain.trajectory


def test_trajectory_rows_stay_as_the_contract_says() -> None:
    run = simulate(parse_scenario(crossing()), 'fastep', 0)
    rows = run.robots[0].to_json()['trajectory']
    assert isinstance(rows, list) and all(len(row) == 3 for row in rows)


def test_margins_measure_movers_at_the_same_instants() -> None:
    movers = Movers([Circle((0.0, -5.0), 1.0)], [Motion(((0.0, 5.0),), 1.0)])   # at (0, 0) at t = 5
    still_robot = np.array([[t, 0.0, 0.0] for t in np.arange(0.0, 10.1, 0.5)])
    late_robot = np.array([[t, 3.0, 0.0] for t in np.arange(0.0, 10.1, 0.5)])
    margins = trajectory_margins([still_robot, late_robot], [0.5, 0.5], Obstacles(), movers)
    np.testing.assert_allclose(margins.obstacles, [-1.5, 1.5])
    # Only the instants count: a robot at the mover's t = 5 place at t = 0 only is not touched.
    early = np.array([[0.0, 0.0, 0.0]])
    assert trajectory_margins([early], [0.5], Obstacles(), movers).obstacles[0] == pytest.approx(3.5)


def test_crossing_movers_builtin() -> None:
    """fastep yields to the mover and arrives clear of the truth. aco used to crawl (about 460 s for 40 m) and sat
    in the mover's lane when it came back; with the approach-speed floor (min_approach_speed, docs/approach_speed.md)
    and its scanner's tracks it now crosses clear of it in this world. The random crossing-movers family is
    docs/dynamic_world.md's ("Measured: the v2 families")."""
    scenario = load_scenario('crossing_movers')
    for seed in range(3):
        robot = simulate(scenario, 'fastep', seed).robots[0]
        assert robot.reached and not robot.collided and robot.min_clearance > 0.5, (seed, robot.status)
    robot = simulate(scenario, 'aco', 0).robots[0]
    assert robot.reached and not robot.collided, robot.status


def test_a_robot_with_a_footprint_is_judged_by_its_outline_at_every_step() -> None:
    from fastep_core.footprint import Footprint
    from fastep_core.simulator import Tick

    box = [[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]]
    data = {'workspace': [0, 0, 8, 4], 'obstacles': [{'circle': {'center': [4.0, 2.6], 'radius': 0.2}}],
            'robots': [{'name': 'r1', 'model': 'diff_drive', 'start': [1.0, 2.0, 0.0], 'goal': [7.0, 2.0],
                        'footprint': box}]}
    scenario = parse_scenario(data)
    poses: list[np.ndarray] = []

    def observe(tick: Tick) -> None:
        poses.append(np.array(tick.state[:3]))

    run = simulate(scenario, 'fastep_route', seed=0, observer=observe)
    robot = run.robots[0]
    footprint = Footprint.parse(box)
    assert robot.reached and not robot.collided
    assert robot.min_clearance == float(footprint.clearance(np.array(poses), scenario.world.obstacles).min())
    # Its disc would have kept less: the box is narrower than its circumscribed circle.
    disc = float(scenario.world.obstacles.clearance(np.array(poses)[:, :2]).min()) - footprint.radius
    assert robot.min_clearance > disc
