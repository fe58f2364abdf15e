"""Property-based tests (hypothesis): geometry identities and the planner's invariants on random worlds."""

import math

import numpy as np
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from fastep_core.geometry import Circle, Obstacles, Segment, point_segment_distance, segment_segment_distance
from fastep_core.planning import OtherRobot, PlannerParams, StepProblem, make_navigator, plan_step
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

coord = st.floats(-50.0, 50.0, allow_nan=False, allow_infinity=False)
point = st.tuples(coord, coord)
circle = st.builds(Circle, point, st.floats(0.1, 5.0))
segment = st.builds(Segment, point, point)
obstacle_lists = st.lists(st.one_of(circle, segment), min_size=1, max_size=8)
SLOW = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow])


def brute_point_segment(p, a, b, n=2001):
    t = np.linspace(0.0, 1.0, n)[:, None]
    return float(np.hypot(*(a + t * (b - a) - p).T).min())


@given(point, point, point)
def test_point_segment_distance_is_the_minimum_over_the_segment(p, a, b):
    p, a, b = (np.array(v) for v in (p, a, b))
    exact = float(point_segment_distance(p, a, b))
    sampled = brute_point_segment(p, a, b)
    assert exact <= sampled + 1e-9
    assert sampled - exact <= np.hypot(*(b - a)) / 2000 + 1e-9   # within the sampling step


@given(point, point, point, point)
def test_segment_distance_is_symmetric_and_bounded_by_endpoint_distances(p0, p1, q0, q1):
    p0, p1, q0, q1 = (np.array(v) for v in (p0, p1, q0, q1))
    d = float(segment_segment_distance(p0, p1, q0, q1))
    assert math.isclose(d, float(segment_segment_distance(q0, q1, p0, p1)), abs_tol=1e-9)
    assert math.isclose(d, float(segment_segment_distance(p1, p0, q1, q0)), abs_tol=1e-9)
    ends = min(float(point_segment_distance(x, q0, q1)) for x in (p0, p1))
    ends = min(ends, *(float(point_segment_distance(x, p0, p1)) for x in (q0, q1)))
    assert 0.0 <= d <= ends + 1e-9


@given(obstacle_lists, point, point)
def test_run_clearance_never_exceeds_the_clearance_of_its_ends(items, a, b):
    obstacles = Obstacles(items)
    run = float(obstacles.path_clearance(np.array(a), np.array(b)))
    ends = obstacles.clearance(np.array([a, b]))
    assert run <= float(ends.min()) + 1e-9
    # ... and it is the minimum of the per-obstacle run distances
    assert math.isclose(run, float(obstacles.path_distances(np.array(a), np.array(b)).min()), abs_tol=1e-12)


@given(obstacle_lists, point, st.floats(0.0, 2 * math.pi), st.floats(0.0, 3.0))
def test_clearance_is_1_lipschitz(items, p, angle, step):
    obstacles = Obstacles(items)
    q = np.array(p) + step * np.array([math.cos(angle), math.sin(angle)])
    c = obstacles.clearance(np.array([p, q]))
    assert abs(float(c[0] - c[1])) <= step + 1e-9


@given(obstacle_lists, point, st.lists(point, min_size=1, max_size=12))
def test_fan_clearance_equals_run_clearance_one_by_one(items, origin, ends):
    obstacles = Obstacles(items)
    fan = obstacles.fan_clearance(np.array(origin), np.array(ends))
    each = [float(obstacles.path_clearance(np.array(origin), np.array(e))) for e in ends]
    assert np.allclose(fan, each, atol=1e-9)


# ----------------------------------------------------------------------------------------- the planner

field = st.lists(st.builds(Circle, st.tuples(st.floats(5.0, 45.0), st.floats(5.0, 45.0)), st.floats(0.3, 4.0)),
                 min_size=1, max_size=10)


@settings(max_examples=40, **SLOW)
@given(field, st.tuples(st.floats(2.0, 48.0), st.floats(2.0, 48.0)), st.integers(0, 2**32 - 1),
       st.sampled_from(['fastep', 'aco']))
def test_a_planned_waypoint_always_keeps_the_clearance(circles, origin, seed, method):
    world = World.from_obstacles([0, 0, 50, 50], circles)
    origin = np.array(origin)
    clearance = 0.7
    assume(float(world.obstacles.clearance(origin)) >= clearance)
    problem = StepProblem(world, origin, np.array([45.0, 45.0]), clearance, 2.0, 0.18, 0.18, 0.01)
    step = plan_step(problem, PlannerParams(), np.random.default_rng(seed), method)
    if step is None:
        return   # no feasible step is an allowed answer; a wrong one is not
    w = step.waypoint
    assert np.hypot(*(w - origin)) <= 2.0 + 1e-9
    assert float(world.obstacles.clearance(w)) >= clearance - 1e-9
    assert float(world.obstacles.path_clearance(origin, w)) >= clearance - 1e-9
    assert float(world.wall_distance(w)) >= min(clearance, float(world.wall_distance(origin))) - 1e-9


@settings(max_examples=30, **SLOW)
@given(field, st.tuples(st.floats(1.0, 49.0), st.floats(1.0, 49.0)),
       st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)),
       st.lists(st.tuples(st.floats(0.0, 50.0), st.floats(0.0, 50.0)), max_size=3), st.integers(0, 1000))
def test_the_guard_never_lets_a_tick_end_inside_an_obstacle_or_another_robot(circles, position, push, others, seed):
    """Whatever the command, a point mass that starts clear never ends a tick within its radius of anything."""
    world = World.from_obstacles([0, 0, 50, 50], circles)
    spec = RobotSpec('r1', 'point_mass', position, (45.0, 45.0), 0.5)
    nav = make_navigator('fastep', spec, 0.5, world, PlannerParams(), seed)
    state = np.array(position)
    robots = [OtherRobot(f'o{i}', p) for i, p in enumerate(others)]
    assume(float(world.obstacles.clearance(state)) >= 0.5)
    assume(all(np.hypot(*(state - p)) >= 1.0 + 0.25 * 0.2 + 1.0 * 0.05 for p in others))
    command = np.array(push) * 20.0   # far more than max_speed: the guard alone decides
    guarded = nav.guard(state, command, 0.05, robots)
    after = nav.model.integrate(state, guarded, 0.05)
    assert float(world.obstacles.clearance(after)) >= 0.5 - 1e-9 or \
        float(world.obstacles.clearance(after)) >= float(world.obstacles.clearance(state))
    for p in others:
        gap_after, gap_now = np.hypot(*(after - p)), np.hypot(*(state - p))
        assert gap_after >= 1.0 or gap_after >= gap_now


@settings(max_examples=15, **SLOW)
@given(field, st.tuples(st.floats(2.0, 48.0), st.floats(2.0, 48.0)), st.floats(-math.pi, math.pi),
       st.floats(-0.8, 0.8))
@example(circles=[Circle((5.0, 5.0), 1.0)], origin=(2.0, 9.0), heading=3.0, hitch=0.25)  # replay folds 1.3 mrad more
def test_a_found_manoeuvre_keeps_its_clearance_and_never_folds_the_trailer(circles, origin, heading, hitch):
    from fastep_core.kinematics import TractorTrailer
    from fastep_core.kinematics.tractor_trailer import hitch_angle
    from fastep_core.planning.recovery.manoeuvre_search import HITCH_SLACK, plan_manoeuvre
    world = World.from_obstacles([0, 0, 50, 50], circles)
    keep = 0.65
    assume(float(world.obstacles.clearance(np.array(origin))) >= keep and min(origin) >= keep
           and max(origin) <= 50 - keep)
    start = [origin[0], origin[1], heading, heading + hitch]
    found = plan_manoeuvre(TractorTrailer(), world, start, [45.0, 45.0], keep, 0.05, max_expansions=1500)
    if found is None:
        return   # none found is an allowed answer; a wrong one is not
    assert float(world.room(found.states[:, :2]).min()) >= keep - 0.02
    # The search holds 1 rad at its sub-steps; the replayed ticks may part from them by HITCH_SLACK.
    assert max(abs(hitch_angle(s)) for s in found.states) <= max(1.0, abs(hitch)) + HITCH_SLACK
