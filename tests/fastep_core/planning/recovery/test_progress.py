"""The progress checker and the trap detector (planning/recovery/progress.py)."""

from __future__ import annotations

from fastep_core.planning.recovery.progress import ProgressChecker, TrapDetector


def test_the_progress_checker_fails_a_run_that_stops_coming_closer():
    check = ProgressChecker(distance=0.5, timeout=10.0)
    check.reset(0.0)
    assert not check.stalled(0.0, 20.0)
    assert not check.stalled(5.0, 19.6)   # 0.4 m closer: not progress, the clock runs on from t = 0
    assert not check.stalled(10.0, 19.6)
    assert check.stalled(10.5, 19.6)
    assert 'not 0.5 m closer' in check.reason and 'in 10 s' in check.reason


def test_progress_of_another_kind_restarts_the_clock_and_zero_disables():
    check = ProgressChecker(distance=0.5, timeout=10.0)
    check.reset(0.0)
    check.stalled(0.0, 20.0)
    check.made_progress(8.0)   # e.g. a shorter way left on an escape path
    assert not check.stalled(17.0, 20.0) and check.stalled(18.5, 20.0)
    never = ProgressChecker(distance=0.5, timeout=0.0)
    never.reset(0.0)
    assert not never.stalled(0.0, 20.0) and not never.stalled(1e6, 20.0)


def test_near_the_goal_half_the_distance_counts_as_progress_for_the_trap_detector():
    trap = TrapDetector(distance=0.5, timeout=20.0)
    trap.reset(0.0)
    assert not trap.trapped(0.0, 0.6)
    assert not trap.trapped(15.0, 0.29)   # 0.31 m closer: more than half of 0.6, progress
    assert trap.since == 15.0
    assert not trap.trapped(30.0, 0.29) and trap.trapped(35.5, 0.29)


def test_a_reset_trap_detector_starts_from_the_given_distance():
    trap = TrapDetector(distance=0.5, timeout=20.0)
    trap.reset(100.0, 10.0)
    assert not trap.trapped(110.0, 9.8) and trap.trapped(120.5, 9.8)
    assert not TrapDetector(0.5, 0.0).trapped(1e6, 10.0)


def test_a_tripped_trap_detector_calls_the_robot_trapped_once_unless_escapes_are_off():
    trap = TrapDetector(distance=0.5, timeout=20.0)
    trap.reset(0.0)
    assert not trap.trapped(0.0, 10.0)
    trap.trip()   # the planner knows the robot is stuck: no waiting for the clock
    assert trap.trapped(1.0, 10.0)
    assert not trap.trapped(2.0, 10.0)
    trap.trip()
    trap.reset(3.0, 10.0)   # a new goal or a left trap forgets it
    assert not trap.trapped(4.0, 10.0)
    off = TrapDetector(distance=0.5, timeout=0.0)
    off.reset(0.0)
    off.trip()
    assert not off.trapped(1.0, 10.0)
