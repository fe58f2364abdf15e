"""A differential-drive base through the navigator's code paths: every algorithm, the trap escape, the
backing-up recovery, and the acceleration limits across stops (issue 14 item 1)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.experiments.random_worlds import diff_drive_data, u_trap_scenario_data
from fastep_core.kinematics.diff_drive import DiffDrive, DiffDriveController
from fastep_core.planning import PlannerParams, make_navigator
from fastep_core.planning.algorithms import ALGORITHMS, drives
from fastep_core.planning.recovery.back_up import BACKUP_SPEED, BackUp
from fastep_core.scenario import RobotSpec, parse_scenario
from fastep_core.simulator import Tick, simulate
from fastep_core.world import World

BASE = RobotSpec('d1', 'diff_drive', (2.0, 10.0, math.pi), (18.0, 10.5), 0.35)
SMALL = {'name': 'small', 'workspace': [0, 0, 20, 20],
         'obstacles': [{'circle': {'center': [10, 10], 'radius': 1.5}},
                       {'segment': {'start': [14, 6], 'end': [14, 9]}}],
         'robots': [{'name': 'd1', 'model': 'diff_drive', 'start': [2, 10, 3.14159], 'goal': [18, 10.5],
                     'radius': 0.35},
                    {'name': 'd2', 'model': 'diff_drive', 'start': [10, 2, 0.0], 'goal': [10.5, 18],
                     'radius': 0.35}]}


def test_make_robot_builds_the_base_with_the_planner_parameters():
    params = PlannerParams(max_speed=0.3, max_turn_rate=1.8, max_acceleration=1.0, max_turn_acceleration=2.0,
                           turn_gain=1.5, speed_gain=0.2)
    nav = make_navigator('fastep', BASE, 0.35, World.from_obstacles([0, 0, 20, 20], []), params)
    assert nav.model == DiffDrive(0.3, 1.8)
    c = nav.controller
    assert isinstance(c, DiffDriveController)
    assert (c.speed_gain, c.turn_gain, c.max_speed, c.max_turn_rate, c.max_acceleration, c.max_turn_acceleration) \
        == (0.2, 1.5, 0.3, 1.8, 1.0, 2.0)
    assert nav.manoeuvring is None   # it turns in place: no tractor-trailer manoeuvres


@pytest.mark.parametrize('algorithm', ALGORITHMS)
def test_every_algorithm_drives_two_bases_to_their_goals_within_the_limits(algorithm):
    assert drives(algorithm, 'diff_drive')
    scenario = parse_scenario(SMALL)
    params = scenario.planner
    commands: dict[str, list[np.ndarray]] = {}

    def observe(tick: Tick) -> None:
        commands.setdefault(tick.name, []).append(tick.command)

    run = simulate(scenario, algorithm, 0, observer=observe)
    for robot in run.robots:
        assert robot.reached and not robot.collided, (robot.name, robot.status)
        rows = np.array(robot.trajectory)
        assert rows.shape[1] == 4 and np.all(np.abs(rows[:, 3]) <= math.pi)
        c = np.array(commands[robot.name])
        assert np.abs(c[:, 0]).max() <= params.max_speed + 1e-9
        assert np.abs(c[:, 1]).max() <= params.max_turn_rate + 1e-9
        if algorithm != 'dwa':   # dwa's window is the limit by construction; the controller's commands:
            change = np.abs(np.diff(np.vstack([np.zeros(2), c]), axis=0))
            moving = (np.abs(c) > 0).any(axis=1)   # a guarded stop is an emergency stop (kinematics/diff_drive.py)
            assert (change[moving, 0] <= params.max_acceleration * params.dt * (1 + 1e-9)).all()
            assert (change[moving, 1] <= params.max_turn_acceleration * params.dt * (1 + 1e-9)).all()


@pytest.mark.parametrize('seed', [0, 3])
def test_a_base_leaves_a_u_trap_along_the_exact_path(seed):
    scenario = parse_scenario(diff_drive_data(u_trap_scenario_data(seed), seed))
    (robot,) = simulate(scenario, 'fastep', 0).robots
    assert robot.reached and not robot.collided and robot.escapes >= 1, robot.status


def test_backing_up_a_base_drives_straight_back_or_forward():
    backup = BackUp(DiffDrive(1.0, 2.0))
    state = np.array([5.0, 5.0, 0.0])
    # The wall is ahead (+x): more room behind.
    command = backup.choose(state, 0.05, lambda points: 9.0 - points[:, 0], lambda command: True)
    assert command.tolist() == [-BACKUP_SPEED, 0.0]


def test_the_controller_is_told_the_command_the_robot_got():
    """A stop (here: arrival) reaches the controller, so its next command starts from rest."""
    nav = make_navigator('fastep', BASE, 0.35, World.from_obstacles([0, 0, 20, 20], []), PlannerParams())
    nav.set_goal(BASE.goal)
    moving = nav.update(0.0, np.array(BASE.start))
    assert isinstance(nav.controller, DiffDriveController)
    assert nav.controller.last.tolist() == moving.tolist() and moving[1] != 0.0
    nav.controller.last = np.array([1.0, 0.5])
    stop = nav.update(0.05, np.array([18.0, 10.45, 0.0]))   # within goal_tolerance
    assert stop.tolist() == [0.0, 0.0] and nav.controller.last.tolist() == [0.0, 0.0]
