"""The hold breaker's clock and backing up (planning/recovery/back_up.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.geometry import Circle, Segment
from fastep_core.kinematics import PointMass, TractorTrailer
from fastep_core.kinematics.diff_drive import DiffDrive
from fastep_core.kinematics.tractor_trailer import hitch_angle
from fastep_core.planning import PlannerParams
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.recovery.back_up import (
    BACKUP_SPEED,
    BACKUP_TIME,
    HOLD_BEFORE_STEP,
    HOLD_RELEASE,
    LOOK_TURN,
    BackUp,
    RecentScans,
    SeenFree,
    StopTimer,
    backup_speed,
    free_room,
    reverse_free,
    swept_centres,
)
from fastep_core.planning.safety.guard import Stop
from fastep_core.sensing.laser import LaserSpec, scan
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


# ------------------------------------------------------------------ reversing only into space seen free (issue 30)
OPEN = World.from_obstacles([0, 0, 20, 20], [])
HORIZON = 1.0   # s: a quarter metre of backing up at BACKUP_SPEED (the recovery's checks look REVERSE_HORIZON ahead)
BASE = DiffDrive(1.0, 2.0)
FACING_EAST = np.array([5.0, 5.0, 0.0])
BACK = np.array([-0.25, 0.0])
LASER_270 = LaserSpec(fov=1.5 * math.pi, beams=271, noise=0.0)
LASER_360 = LaserSpec(noise=0.0)


def seen(spec, pose, circles=None, radii=None):
    return SeenFree.of_scans([(scan(spec, pose, circles=circles, radii=radii), pose)])


@pytest.mark.parametrize('model, state, command', [
    (BASE, np.array([1.0, 2.0, 0.7]), np.array([-0.25, 0.4])),
    (TractorTrailer(), np.array([1.0, 2.0, 0.7, 0.5]), np.array([-0.25, 0.3])),
    (PointMass(), np.array([1.0, 2.0]), np.array([-0.2, 0.1])),
])
def test_the_swept_path_is_where_the_model_drives(model, state, command):
    path = swept_centres(model, state, command, 2.0, 0.05)
    assert np.hypot(*np.diff(path, axis=0).T).max() <= 0.05
    probe = state
    for _ in range(40):
        probe = model.integrate(probe, command, 0.05)
    assert path[0] == pytest.approx(state[:2]) and path[-1] == pytest.approx(probe[:2], abs=1e-9)


def test_reversing_is_refused_where_the_laser_is_blind_and_allowed_where_it_saw():
    """The report: it reversed with the rear 90 degrees of its laser blind."""
    blind = seen(LASER_270, FACING_EAST)
    assert not reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, blind)
    assert reverse_free(BASE, FACING_EAST, 0.3, -BACK, HORIZON, OPEN, blind)   # forward: seen
    assert reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, seen(LASER_360, FACING_EAST))
    # A scan taken a moment earlier, facing the other way (before the robot turned), saw the space behind.
    earlier = (5.0, 5.0, math.pi)
    both = SeenFree.of_scans([(scan(LASER_270, FACING_EAST), FACING_EAST), (scan(LASER_270, earlier), earlier)])
    assert reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, both)
    assert not reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, SeenFree.of_scans([]))


def test_reversing_is_refused_into_what_the_laser_saw_even_off_the_map():
    behind = seen(LASER_360, FACING_EAST, circles=[[4.45, 5.0]], radii=[0.1])   # 0.15 m behind; off the map
    assert not reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, behind)
    assert reverse_free(BASE, FACING_EAST, 0.3, BACK, 0.2, OPEN, behind)   # 5 cm back keeps 10 cm from it
    beside = seen(LASER_360, FACING_EAST, circles=[[5.0, 6.0]], radii=[0.2])   # abeam: out of the way
    assert reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, beside)


def test_reversing_is_refused_into_the_map_s_obstacles_robots_and_border_with_or_without_a_laser():
    wall = World.from_obstacles([0, 0, 20, 20], [Segment((4.6, 3.0), (4.6, 7.0))])
    everything = seen(LASER_360, FACING_EAST)   # a stale scan that did not see the wall
    for evidence in (None, everything):
        assert reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, evidence)
        assert not reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, wall, evidence)
        other = [OtherRobot('r2', (4.3, 5.1), (0.0, 0.0), 0.3)]
        assert not reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, evidence, other)
        at_border = np.array([0.5, 5.0, 0.0])
        assert not reverse_free(BASE, at_border, 0.3, BACK, HORIZON, OPEN, None)
    # A robot already too near may back away (it comes no nearer), not closer.
    touching = World.from_obstacles([0, 0, 20, 20], [Circle((5.4, 5.0), 0.2)])   # 0.2 m from the robot's centre
    assert reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, touching)
    assert not reverse_free(BASE, FACING_EAST, 0.3, -BACK, HORIZON, touching)
    assert not reverse_free(BASE, FACING_EAST, 0.3, np.array([math.nan, 0.0]), HORIZON, OPEN)


def test_a_full_turn_scan_covers_the_bearing_where_its_beams_wrap_round():
    full = seen(LASER_360, (5.0, 5.0, 0.3))
    ring = np.array([[5.0 + math.cos(a), 5.0 + math.sin(a)] for a in np.linspace(-math.pi, math.pi, 721)])
    assert full.covers(ring).all() and not full.covers(np.array([[5.0 + 11.0, 5.0]])).any()   # range_max 10
    narrow = seen(LaserSpec(fov=0.5, beams=11, noise=0.0), (5.0, 5.0, 0.0))
    assert list(narrow.covers(np.array([[6.0, 5.0], [6.0, 5.3], [6.0, 4.7], [4.0, 5.0]]))) == \
        [True, False, False, False]   # 0.29 rad off the axis of a 0.5 rad fan: outside it


def test_recent_scans_forget_what_is_older_than_keep():
    recent = RecentScans(keep=2.0)
    earlier = (5.0, 5.0, math.pi)
    recent.add(scan(LASER_270, earlier, t=0.0), earlier)
    assert reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, _with(recent, 1.5))
    assert not reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, _with(recent, 2.5))


def test_recent_scans_keep_the_way_the_robot_came_while_it_stands():
    recent = RecentScans(keep=30.0)
    earlier = (5.0, 5.0, math.pi)   # looking back the way it will back up into
    recent.add(scan(LASER_270, earlier, t=0.0), earlier)
    for k in range(1, 100):         # 10 s of scans from where it stands, facing east: nothing new is seen
        recent.add(scan(LASER_270, FACING_EAST, t=0.1 * k), FACING_EAST)
    assert len(recent.scans) == 2
    assert reverse_free(BASE, FACING_EAST, 0.3, BACK, HORIZON, OPEN, recent.seen())


def _with(recent: RecentScans, t: float) -> SeenFree:
    recent.add(scan(LASER_270, FACING_EAST, t=t), FACING_EAST)
    return recent.seen()


def test_backing_up_keeps_to_max_reverse_speed():
    assert backup_speed(PlannerParams()) == BACKUP_SPEED   # the default changes no existing run
    assert backup_speed(PlannerParams(max_reverse_speed=0.1)) == 0.1
    assert backup_speed(PlannerParams(max_reverse_speed=1.0)) == BACKUP_SPEED
    assert backup_speed(PlannerParams(max_reverse_speed=0.0)) == BACKUP_SPEED
    backup = BackUp(BASE, backup_speed(PlannerParams(max_reverse_speed=0.1)))
    backup.start(0.0)
    command = backup.drive(FACING_EAST, 0.05, lambda p: free_room(OPEN, p, []), lambda c: c)
    assert abs(command[0]) == pytest.approx(0.1)
    holonomic = BackUp(PointMass(), 0.1)
    world = World.from_obstacles([0, 0, 20, 20], [Circle((6.0, 5.0), 0.5)])
    away = holonomic.choose(np.array([5.0, 5.0]), 0.05, lambda p: free_room(world, p, []), lambda c: True)
    assert np.hypot(*away) == pytest.approx(0.1)


def test_backing_up_with_evidence_moves_only_into_space_seen_free():
    wall_ahead = World.from_obstacles([0, 0, 20, 20], [Segment((5.5, 3.0), (5.5, 7.0))])
    blind = seen(LASER_270, FACING_EAST, circles=None)

    def free(command):
        return reverse_free(BASE, FACING_EAST, 0.3, command, HORIZON, wall_ahead, blind)

    def room(points):
        return free_room(wall_ahead, points, [])

    backup = BackUp(BASE)
    backup.start(0.0)
    out = backup.drive(FACING_EAST, 0.05, room, lambda c: c, free)
    # Nothing seen behind, the wall ahead: it turns in place to see behind, the recovery going on.
    assert out.tolist() == [0.0, LOOK_TURN] and backup.looking and backup.active(0.1)
    seen_behind = SeenFree.of_scans([(scan(LASER_270, FACING_EAST), FACING_EAST),
                                     (scan(LASER_270, (5.0, 5.0, math.pi)), (5.0, 5.0, math.pi))])
    backup.start(0.0)
    out = backup.drive(FACING_EAST, 0.05, room, lambda c: c,
                       lambda c: reverse_free(BASE, FACING_EAST, 0.3, c, HORIZON, wall_ahead, seen_behind))
    assert out[0] == pytest.approx(-BACKUP_SPEED) and backup.active(0.1)
