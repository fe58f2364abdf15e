"""Tractor-trailer manoeuvres (hybrid A*): they keep their clearance, never fold the trailer, and end where
plain kinematic driving reaches the goal."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.geometry import Circle, Segment
from fastep_core.kinematics import TractorTrailer
from fastep_core.kinematics.tractor_trailer import hitch_angle, wrap_angle
from fastep_core.planning.recovery import manoeuvre_search
from fastep_core.planning.recovery.manoeuvre_search import DistanceField, plan_manoeuvre
from fastep_core.world import World

MODEL = TractorTrailer(1.0, 1.0, 0.0)
DT = 0.05


def pocket(width: float) -> World:
    """A dead end open towards -x: walls along y = 10 -+ width/2 from x = 4 to 12, closed at x = 12."""
    lo, hi = 10.0 - width / 2, 10.0 + width / 2
    return World((0.0, 0.0, 20.0, 20.0), (Segment((4.0, lo), (12.0, lo)), Segment((12.0, lo), (12.0, hi)),
                                          Segment((12.0, hi), (4.0, hi))))


@pytest.mark.parametrize('width', [4.0, 1.6])
def test_a_manoeuvre_out_of_a_dead_end_keeps_its_clearance_and_the_trailer_straight(width: float) -> None:
    world, goal, keep = pocket(width), np.array([2.0, 10.0]), 0.65
    found = plan_manoeuvre(MODEL, world, [10.5, 10.0, 0.0, 0.0], goal, keep, DT)
    assert found is not None and found.ticks == len(found.commands) == len(found.states) - 1
    assert world.room(found.states[:, :2]).min() >= keep - 0.02
    assert max(abs(hitch_angle(s)) for s in found.states) <= 1.0 + 1e-6
    # The states are the plant's: replaying the commands with the model's integrator gives them back.
    state = found.states[0]
    for command in found.commands:
        state = MODEL.integrate(state, command, DT)
    assert np.allclose(state, found.states[-1])
    end = found.states[-1]
    ahead = abs(math.remainder(math.atan2(goal[1] - end[1], goal[0] - end[0]) - end[2], 2 * math.pi))
    assert math.dist(end[:2], goal) <= 1.0 or (ahead <= math.radians(30) and end[0] < 4.0)
    if width == 1.6:
        # Too narrow to turn (the reference point has 0.15 m either side): it has to reverse out.
        assert (found.commands[:, 0] < 0).any()


def test_no_manoeuvre_to_a_walled_in_goal() -> None:
    ring = tuple(Circle((10.0 + 3 * math.cos(a), 10.0 + 3 * math.sin(a)), 0.9)
                 for a in np.linspace(0, 2 * np.pi, 13)[:-1])
    world = World((0.0, 0.0, 20.0, 20.0), ring)
    assert plan_manoeuvre(MODEL, world, [2.0, 2.0, 0.0, 0.0], [10.0, 10.0], 0.6, DT) is None


def test_distance_field_is_straight_in_the_open_and_goes_round_a_wall() -> None:
    open_field = DistanceField(World((0.0, 0.0, 20.0, 20.0)), [15.0, 10.0], keep=0.5)
    assert open_field(np.array([[5.0, 10.0]]))[0] == pytest.approx(10.0, abs=0.3)
    wall = World((0.0, 0.0, 20.0, 20.0), (Segment((10.0, 2.0), (10.0, 18.0)),))
    around = DistanceField(wall, [15.0, 10.0], keep=0.5)
    # Round the wall's end at (10, 18): at least the two straight legs via that end.
    legs = math.dist((5.0, 10.0), (10.0, 18.5)) + math.dist((10.0, 18.5), (15.0, 10.0))
    assert around(np.array([[5.0, 10.0]]))[0] >= legs - 0.5
    assert math.isinf(DistanceField(World((0.0, 0.0, 20.0, 20.0), (Segment((10.0, 0.0), (10.0, 20.0)),)),
                                    [15.0, 10.0], keep=0.5)(np.array([[5.0, 10.0]]))[0])


def test_from_against_a_wall_no_tick_gets_nearer_within_the_floor() -> None:
    """A robot the guard held at a wall starts nearer than keep: the manoeuvre may not take it nearer than it
    is, and no tick may end within the floor (its radius) while getting nearer, which the guard would stop."""
    world, floor, keep = pocket(4.0), 0.5, 0.65
    start = [10.0, 11.49, 0.3, 0.3]       # 0.51 m from the wall at y = 12, heading towards it
    found = plan_manoeuvre(MODEL, world, start, [2.0, 10.0], keep, DT, floor=floor)
    assert found is not None
    rooms = world.room(found.states[:, :2])
    assert rooms[0] == pytest.approx(0.51)
    assert not np.any((rooms[1:] < floor) & (rooms[1:] < rooms[:-1]))
    assert rooms.min() >= 0.51 - 1e-3 - 0.02


def test_the_replay_may_fold_the_trailer_only_hitch_slack_past_the_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    """Facing a wall 2 m away with the trailer folded, the way round holds 1 rad at the search's sub-steps
    and folds 1.3 mrad more when replayed tick by tick; without the slack that replay is refused."""
    world = World.from_obstacles([0.0, 0.0, 50.0, 50.0], [Circle((5.0, 5.0), 1.0)])
    start, goal = [2.0, 9.0, 3.0, 3.25], [45.0, 45.0]
    found = plan_manoeuvre(MODEL, world, start, goal, 0.65, DT, max_expansions=1500)
    assert found is not None
    assert 1.0 < max(abs(hitch_angle(s)) for s in found.states) <= 1.0 + manoeuvre_search.HITCH_SLACK
    monkeypatch.setattr(manoeuvre_search, 'HITCH_SLACK', 0.0)
    assert plan_manoeuvre(MODEL, world, start, goal, 0.65, DT, max_expansions=1500) is None


def test_a_goal_near_but_behind_is_not_reached_by_an_empty_manoeuvre():
    """'Within reach' counted even behind the tractor, inside its turning circle: the search returned no
    manoeuvre at all, and a goal 1 m behind was orbited until the run failed (issue 15, item 23)."""
    world = World((0.0, 0.0, 50.0, 50.0), ())
    found = plan_manoeuvre(TractorTrailer(), world, [25.0, 25.0, 0.0, 0.0], [24.0, 25.0], keep=0.65, dt=0.05)
    assert found is not None and found.ticks > 0
    end = found.states[-1]
    bearing = math.atan2(25.0 - end[1], 24.0 - end[0])
    assert abs(wrap_angle(bearing - end[2])) <= math.radians(30.0) + 1e-9


@pytest.mark.parametrize('bearing', [180.0, 90.0])
def test_a_tractor_trailer_reaches_a_goal_one_metre_behind_or_beside_it(bearing):
    from fastep_core.scenario import parse_scenario
    from fastep_core.simulator import simulate
    b = math.radians(bearing)
    data = {'name': 'behind', 'workspace': [0, 0, 50, 50], 'obstacles': [],
            'robots': [{'name': 'r1', 'model': 'tractor_trailer', 'start': [25, 25, 0, 0],
                        'goal': [25 + math.cos(b), 25 + math.sin(b)], 'radius': 0.6, 'length': 1.0,
                        'trailer_length': 1.0, 'width': 0.5}]}
    robot = simulate(parse_scenario(data), 'fastep', 0).robots[0]
    assert robot.reached and not robot.collided, robot.status
