"""One-lane passages on a route and who waits before one (fastep_core/planning/safety/passage.py, FAStep-Route)."""

import numpy as np
import pytest

from fastep_core.geometry import Circle, Segment
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.safety.passage import Passage, passages
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.scenario import parse_scenario
from fastep_core.simulator import simulate
from fastep_core.world import World

LINE = np.array([[2.0, 10.0], [38.0, 10.0]])   # a route straight through the corridor below, left to right


def corridor(gap):
    """A corridor from x = 15 to 25 whose walls are `gap` metres apart, in a 40 x 20 m workspace."""
    return World.from_obstacles([0, 0, 40, 20], [Segment((15.0, 10.0 + gap / 2), (25.0, 10.0 + gap / 2)),
                                                  Segment((15.0, 10.0 - gap / 2), (25.0, 10.0 - gap / 2))])


def test_a_corridor_too_narrow_to_pass_beside_is_one_passage_along_its_length():
    found = passages(corridor(2.4), LINE, 0.5, 0.5, 0.2)
    assert len(found) == 1
    passage = found[0]
    # Narrow a little before and after the walls' ends (a robot beside would touch an end), never far from them.
    assert 12.0 < passage.entry <= 13.0 and 23.0 <= passage.exit < 24.0
    assert passage.points[0][0] == pytest.approx(2.0 + passage.entry)
    assert passage.far_end[0] == pytest.approx(2.0 + passage.exit)


@pytest.mark.parametrize('world', [corridor(8.0), World.from_obstacles([0, 0, 40, 20], [])])
def test_room_beside_the_route_makes_no_passage(world):
    assert passages(world, LINE, 0.5, 0.5, 0.2) == []


def test_a_bigger_other_robot_needs_more_room():
    assert passages(corridor(5.0), LINE, 0.5, 0.5, 0.2) == []
    assert len(passages(corridor(5.0), LINE, 0.5, 1.5, 0.2)) == 1


PASSAGE = Passage(10.0, 20.0, np.stack([np.linspace(15.0, 25.0, 41), np.full(41, 10.0)], axis=1))
HERE = np.array([11.0, 10.0])   # 4 m before the entry, driving right


def robot(name, x, vx, y=10.0):
    return OtherRobot(name, (x, y), (vx, 0.0), 0.5)


@pytest.mark.parametrize('other,waits', [
    (robot('r2', 22.0, -1.0), True),    # in the passage, coming this way
    (robot('r2', 22.0, 1.0), False),    # in it, going the same way: follow it in
    (robot('r2', 22.0, 0.0), False),    # standing in it: the route goes round it, not waited for
    (robot('r2', 28.0, -1.0), True),    # 3 m from the far end, coming: nearer than this robot's 4 m
    (robot('r2', 30.0, -1.0), False),   # 5 m from it: this robot goes first
    (robot('r2', 30.0, 1.0), False),    # 5 m from it and leaving
    (robot('r0', 29.2, -1.0), True),    # a tie (4.2 against 4 m): the name that sorts first goes first ...
    (robot('r2', 29.2, -1.0), False),   # ... this robot is r1
    (robot('r2', 11.0, -1.0, y=4.0), False),   # far from either end, passing by
])
def test_who_waits_before_a_passage(other, waits):
    found = PASSAGE.conflict(HERE, 'r1', [other], 0.05, 0.5, 0.2)
    assert (found is other) if waits else found is None


def test_a_robot_standing_at_the_far_end_is_waited_for_only_by_one_already_waiting_and_only_if_it_goes_first():
    # Both took the other for the nearer one and stood: the name decides, so they do not both go and stand again.
    standing = robot('r0', 27.0, 0.0)
    assert PASSAGE.conflict(HERE, 'r1', [standing], 0.05, 0.5, 0.2, waiting=True) is standing
    assert PASSAGE.conflict(HERE, 'r1', [standing], 0.05, 0.5, 0.2, waiting=False) is None   # parked there for good?
    assert PASSAGE.conflict(HERE, 'r1', [robot('r2', 27.0, 0.0)], 0.05, 0.5, 0.2, waiting=True) is None
    assert PASSAGE.conflict(HERE, 'r1', [robot('r0', 35.0, 0.0)], 0.05, 0.5, 0.2, waiting=True) is None   # far


@pytest.mark.parametrize('bad', [OtherRobot('r2', (22.0, 10.0), (float('nan'), float('nan')), 0.5),
                                 OtherRobot('r2', (float('nan'), 10.0), (-1.0, 0.0), 0.5),
                                 OtherRobot('r2', (22.0, 10.0), (-1.0, 0.0), float('nan'))])
def test_a_robot_with_a_non_finite_pose_velocity_or_radius_is_left_out(bad):
    assert PASSAGE.conflict(HERE, 'r1', [bad], 0.05, 0.5, 0.2) is None


def test_the_samples_lie_on_one_grid_along_the_route_whatever_the_window():
    world = corridor(2.4)
    whole = passages(world, LINE, 0.5, 0.5, 0.2)
    for start in (0.0, 3.14, 10.07, 12.2):
        part = passages(world, LINE, 0.5, 0.5, 0.2, start, start + 60.0)
        assert [(p.entry, p.exit) for p in part] == [(p.entry, p.exit) for p in whole]
    # A window beginning or ending inside it: the passage begins or ends there, on the grid.
    assert [(p.entry, p.exit) for p in passages(world, LINE, 0.5, 0.5, 0.2, 12.9, 60.0)] == [(13.0, whole[0].exit)]
    assert [(p.entry, p.exit) for p in passages(world, LINE, 0.5, 0.5, 0.2, 0.0, 18.0)] == [(whole[0].entry, 18.0)]


def test_repeated_vertices_make_no_false_passage():
    world = World.from_obstacles([0, 0, 40, 20], [Circle((20.0, 11.2), 0.5)])
    assert passages(world, np.array([[2.0, 10.0], [20.0, 10.0], [20.0, 10.0]]), 0.5, 0.5, 0.2) == []
    assert passages(world, np.array([[2.0, 10.0], [2.0, 10.0]]), 0.5, 0.5, 0.2) == []


def test_two_robots_of_different_sizes_judge_a_place_alike():
    world = corridor(4.2)
    assert [(p.entry, p.exit) for p in passages(world, LINE, 0.3, 0.7, 0.2)] == \
        [(p.entry, p.exit) for p in passages(world, LINE, 0.7, 0.3, 0.2)]


def head_on(gap, model='point_mass'):
    turn = [] if model == 'point_mass' else [0.0]
    back = [] if model == 'point_mass' else [np.pi]
    return parse_scenario({
        'name': 'corridor', 'workspace': [0, 0, 40, 20],
        'obstacles': [{'segment': {'start': [15, 10 + gap / 2], 'end': [25, 10 + gap / 2]}},
                      {'segment': {'start': [15, 10 - gap / 2], 'end': [25, 10 - gap / 2]}}],
        'robots': [{'name': 'r1', 'model': model, 'start': [4, 10] + turn, 'goal': [36, 10.5], 'radius': 0.5},
                   {'name': 'r2', 'model': model, 'start': [37, 9.5] + back, 'goal': [3, 10], 'radius': 0.5}]})


@pytest.mark.parametrize('model', ['point_mass', 'diff_drive'])
def test_two_robots_head_on_in_a_corridor_take_turns(model):
    """Without the rule the two point masses met in the 2.4 m corridor and came through 2.6-3.0 x their optimum
    or not at all (max_sim_time); two diff-drive bases 1.04-1.15 x, 0.03 m apart."""
    scenario = head_on(2.4, model)
    statuses = {}
    run = simulate(scenario, 'fastep_route', 0,
                   observer=lambda tick: statuses.setdefault(tick.name, set()).add(tick.navigator.reason))
    for result, spec in zip(run.robots, scenario.robots):
        assert result.reached and not result.collided, result.status
        optimum = shortest_path(scenario.world, spec.start[:2], spec.goal,
                                spec.radius + scenario.planner.clearance_margin)
        assert result.path_length < 1.01 * optimum.length
    # r1 is 11 m from the corridor, r2 12 m: r2 waits for r1 to come through, r1 never waits
    assert 'waiting for r1 to come through the passage' in statuses['r2']
    assert not any('passage' in reason for reason in statuses['r1'])


def test_a_robot_waits_at_most_passage_wait_seconds_for_one_that_never_comes_through():
    from fastep_core.planning import Mode, PlannerParams
    from fastep_core.planning.algorithms import make_navigator
    from fastep_core.planning.navigators.fastep_route import PASSAGE_WAIT
    from fastep_core.scenario import RobotSpec
    spec = RobotSpec('r1', 'point_mass', (4.0, 10.0), (36.0, 10.0), 0.5)
    nav = make_navigator('fastep_route', spec, 0.5, corridor(2.4), PlannerParams(), 0)
    nav.set_goal((36.0, 10.0))
    stuck = OtherRobot('r2', (21.0, 10.0), (-0.5, 0.0), 0.5)   # in the corridor, "coming", never getting anywhere
    state, waited = np.array([4.0, 10.0]), []
    for k in range(int((PASSAGE_WAIT + 20.0) / nav.params.dt)):
        t = k * nav.params.dt
        command = nav.update(t, state, [stuck])
        if nav.reason == 'waiting for r2 to come through the passage':
            waited.append(t)
        if nav.mode in (Mode.ARRIVED, Mode.FAILED):
            break
        state = nav.model.integrate(state, command, nav.params.dt)
    assert waited and waited[-1] - waited[0] == pytest.approx(PASSAGE_WAIT, abs=2 * nav.params.dt)
    assert state[0] > 13.0   # it went on towards the passage after that
