"""The robot harness (fastep_testing/robot_harness.py): its measurements on synthetic data, and one live run.

The live run starts the wall-time base and fastep-planner on an isolated domain and drives the shortest world
to its goal: it asserts arrival and no collision against the true world, never a time (it must pass on a loaded
2-core machine), and run_world stops both processes before it returns. tests/conftest.py runs this file with
the live-graph tests, one after another.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from fastep_testing import robot_measures as measures
from fastep_testing.robot_harness import HarnessResult, judge, run_world
from fastep_testing.robot_worlds import WORLDS, world


def test_gaps_count_the_silences_longer_than_the_threshold_and_give_the_longest() -> None:
    times = np.concatenate([np.arange(0.0, 1.0, 0.05), 1.3 + np.arange(0.0, 1.0, 0.05), [2.45]])
    gaps = measures.command_gaps(times, 0.15)
    assert (gaps.count, round(gaps.longest, 9)) == (2, round(1.3 - 0.95, 9))
    assert measures.command_gaps(times, 0.4).count == 0
    assert measures.command_gaps([1.0], 0.1) == measures.Gaps(0.1, 0, 0.0)


def test_accelerations_between_commands_are_steps_over_the_time_between_them() -> None:
    t = np.arange(11) * 0.05
    v = np.minimum(t * 2.0, 0.6)             # 2 m/s^2 up to 0.6 m/s
    omega = np.where(t > 0.3, -0.5, 0.0)     # one step of 0.5 rad/s
    dv, dw = measures.command_accelerations(t, v, omega)
    assert dv == pytest.approx(2.0) and dw == pytest.approx(10.0)
    # Two commands taken at once: the step counts over min_dt, not over zero.
    assert measures.command_accelerations([0.0, 0.0], [0.0, 0.01], [0.0, 0.0]) == pytest.approx((10.0, 0.0))
    assert measures.command_accelerations([0.0], [1.0], [1.0]) == (0.0, 0.0)


def test_accelerations_over_several_commands_weigh_a_jittered_arrival_less() -> None:
    t = np.arange(21) * 0.05
    t[10] -= 0.004                           # one command 4 ms early
    v = np.arange(21) * 0.125                # 2.5 m/s^2 at 20 Hz
    assert measures.command_accelerations(t, v, v)[0] == pytest.approx(0.125 / 0.046)
    assert measures.command_accelerations(t, v, v, span=5)[0] == pytest.approx(0.625 / 0.246)
    assert measures.command_accelerations(t[:5], v[:5], v[:5], span=5) == (0.0, 0.0)


def test_proc_stat_is_read_after_the_last_parenthesis_of_the_command_name() -> None:
    fields = ' '.join(['S'] + [str(k) for k in range(4, 14)] + ['120', '30'] + ['0'] * 30)
    assert measures.parse_proc_stat(f'4242 (python (x) y) {fields}') == 150
    assert measures.process_cpu_seconds(os.getpid()) > 0.0
    assert measures.cpu_percent(1.0, 1.5, 5.0) == pytest.approx(10.0)
    assert math.isnan(measures.cpu_percent(1.0, 1.5, 0.0))


def test_control_ms_is_read_from_the_planner_status_value() -> None:
    assert measures.parse_control_ms('1.250 / 4.500 / 22.000') == (1.25, 4.5, 22.0)
    assert measures.parse_control_ms('') is None
    assert measures.parse_control_ms('a / b / c') is None


def test_judge_measures_the_true_track_the_commands_and_the_statuses() -> None:
    scenario = world('open_room')   # walls 0.1 m inside a 10 m x 6 m workspace
    t = np.arange(0.0, 5.0, 0.01)
    x = 1.5 + t * 1.4
    track = np.column_stack([t, x, np.full_like(t, 3.0), np.zeros_like(t), np.full_like(t, 1.4), np.zeros_like(t)])
    commands = np.column_stack([np.arange(0.0, 5.0, 0.05), np.full(100, 1.4), np.zeros(100)])
    commands = np.delete(commands, [40, 41, 42, 43], axis=0)              # a 0.25 s gap
    statuses = [(0.5, {'message': 'kinematic', 'control_ms': '1 / 3 / 9', 'control_cpu_ms': '1 / 2 / 8'}),
                (4.0, {'message': 'arrived', 'reason': 'goal reached', 'control_ms': '1 / 4 / 7', 'scans': '80'})]
    result = judge(HarnessResult('open_room', True), scenario, commands, track, statuses, (0.0, 5.0),
                   {'planner': (1.0, 1.5)})
    assert result.arrived and result.time_to_goal == 4.0 and result.status == 'arrived'
    # The nearest wall: the one behind the start (1.4 m) or the far one at the end, less the 0.3 m radius.
    assert result.min_clearance == pytest.approx(min(1.4, 9.9 - x[-1]) - 0.3) and not result.collided
    assert (result.gaps_over_015, result.gaps_over_2_periods, round(result.longest_gap, 9)) == (1, 1, 0.25)
    assert (result.control_p99_ms, result.control_max_ms, result.control_cpu_p99_ms) == (4.0, 9.0, 2.0)
    assert result.planner_cpu == pytest.approx(10.0) and result.scans == 80
    crash = track.copy()
    crash[:, 1] = 1.5 + t * 2.0             # through the far wall
    assert judge(HarnessResult('open_room', True), scenario, commands, crash, statuses, (0.0, 5.0), {}).collided


def test_the_worlds_are_one_diff_drive_robot_and_open_room_is_the_shortest() -> None:
    lengths = {}
    for name, scenario in WORLDS.items():
        (robot,) = scenario.robots
        assert robot.model == 'diff_drive'
        lengths[name] = math.dist(robot.start[:2], robot.goal)
    assert min(lengths, key=lengths.__getitem__) == 'open_room'
    assert not WORLDS['unmapped_box'].is_static   # the box is in the truth, not on the map


def test_a_heavy_base_on_wall_time_stops_at_a_goal_before_a_wall() -> None:
    """The report: a 40 kg base on weak motors arrived at 0.9 m/s and hit the wall 0.45 m behind its goal."""
    result = run_world('wall_ahead', dynamics='heavy', timeout=90.0, start_timeout=90.0)
    assert result.arrived, result
    assert not result.collided and result.min_clearance > 0.0, result
    assert result.final_distance < 0.2 and result.arrival_speed < 0.5, result


def test_the_planner_drives_the_wall_time_base_to_the_goal_of_the_shortest_world() -> None:
    result = run_world('open_room', timeout=90.0, start_timeout=90.0)
    assert result.arrived, result
    assert not result.collided and result.min_clearance > 0.0, result
    assert result.commands > 0 and result.final_distance < 0.5, result
