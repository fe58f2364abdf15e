"""The hold breaker's clock and backing up (planning/recovery.py)."""

from __future__ import annotations

import math

import numpy as np

from fastep_core.geometry import Circle, Segment
from fastep_core.kinematics import PointMass, TractorTrailer
from fastep_core.kinematics.tractor_trailer import hitch_angle
from fastep_core.planning.guard import Stop
from fastep_core.planning.recovery import (
    BACKUP_SPEED,
    BACKUP_TIME,
    HOLD_BEFORE_STEP,
    HOLD_RELEASE,
    BackUp,
    StopTimer,
    free_room,
)
from fastep_core.world import World

HERE = np.zeros(2)


def test_a_robot_held_for_another_gets_its_step_after_hold_before_step():
    timer = StopTimer()
    assert not timer.stopped(0.0, Stop.ROBOT, HERE) and not timer.hold_breaker_due(0.5)
    assert timer.hold_breaker_due(HOLD_BEFORE_STEP) and not timer.hold_breaker_due(HOLD_BEFORE_STEP + 0.1)
    timer.moved(np.array([HOLD_RELEASE, 0.0]))
    assert timer.held_since is None and timer.stuck_since is None


def test_stuck_comes_after_one_hold_at_a_wall_and_three_at_a_robot():
    wall, robot = StopTimer(), StopTimer()
    assert not wall.stopped(0.0, Stop.OBSTACLE, HERE) and wall.stopped(HOLD_BEFORE_STEP, Stop.OBSTACLE, HERE)
    assert not robot.stopped(0.0, Stop.ROBOT, HERE) and not robot.stopped(2 * HOLD_BEFORE_STEP, Stop.ROBOT, HERE)
    assert robot.stopped(3 * HOLD_BEFORE_STEP, Stop.ROBOT, HERE)
    assert robot.stuck_since is None   # the clock starts again after the recovery


def test_turns_and_twitches_between_stops_do_not_restart_the_clocks():
    """Two diff-drive robots face to face: every other tick a turn in place or a 2 cm step got through, and the
    timers restarted each time, so neither robot ever backed up (diff_drive_robots worlds 1000015, 1000019)."""
    timer = StopTimer()
    t, position = 0.0, np.zeros(2)
    recovery_due = False
    while t < 3 * HOLD_BEFORE_STEP + 0.1 and not recovery_due:
        recovery_due = timer.stopped(t, Stop.ROBOT, position)
        position = position + np.array([0.002, 0.0])   # a command got through: 2 mm
        timer.moved(position)
        t += 0.1
    assert recovery_due and float(position[0]) < HOLD_RELEASE
    timer.stopped(10.0, Stop.ROBOT, HERE)
    timer.moved(np.array([0.0, HOLD_RELEASE]))   # a real way out ends the stop
    assert timer.held_since is None and timer.stuck_since is None and timer.where is None


def test_a_holonomic_robot_backs_straight_away_from_what_is_nearest():
    world = World.from_obstacles([0, 0, 20, 20], [Circle((6.0, 5.0), 0.5)])
    backup = BackUp(PointMass())
    backup.start(10.0)
    assert backup.active(10.0 + BACKUP_TIME - 0.01) and not backup.active(10.0 + BACKUP_TIME)
    command = backup.choose(np.array([5.0, 5.0]), 0.05, lambda p: free_room(world, p, []), lambda c: True)
    assert math.isclose(float(np.hypot(*command)), BACKUP_SPEED) and command[0] < 0 and abs(command[1]) < 1e-6


def test_a_tractor_trailer_facing_a_wall_backs_up_and_keeps_its_choice():
    model = TractorTrailer()
    world = World.from_obstacles([0, 0, 20, 20], [Segment((6.2, 3.0), (6.2, 7.0))])
    state = np.array([5.0, 5.0, 0.0, 0.0])
    backup = BackUp(model)
    backup.start(0.0)

    def room(points):
        return free_room(world, points, [])

    first = backup.choose(state, 0.05, room, lambda c: c[0] < 0)   # the guard allows reversing only
    assert first[0] < 0
    probe = state
    for _ in range(int(BACKUP_TIME / 0.05)):
        probe = model.integrate(probe, first, 0.05)
    assert abs(hitch_angle(probe)) <= 1.0
    assert backup.choose(probe, 0.05, room, lambda c: True) is first   # chosen once per recovery


def test_a_refused_backup_ends_the_recovery():
    backup = BackUp(PointMass())
    backup.start(0.0)
    world = World.from_obstacles([0, 0, 20, 20], [Circle((6.0, 5.0), 0.5)])
    out = backup.drive(np.array([5.0, 5.0]), 0.05, lambda p: free_room(world, p, []), lambda c: np.zeros(2))
    assert np.all(out == 0.0) and not backup.active(0.1)
