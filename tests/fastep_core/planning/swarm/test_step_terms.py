"""StepProblem.terms, the fast eq. 10, returns the same floats bit for bit as the plain formulation; so does
StepProblem.fitness, which computes eq. 10 for the feasible candidates only.

The swarm compares fitness values, so one different last bit can change a move and with it a trajectory;
fastep_testing/step_reference.py is eq. 10 and the clearance rule written one numpy expression per term.
"""

import dataclasses

import numpy as np
import pytest

from fastep_core.geometry import Circle, Segment
from fastep_core.planning import StepProblem
from fastep_core.planning.swarm.step import INFEASIBLE
from fastep_core.world import World
from fastep_testing.step_reference import reference_terms

SIDE = 30.0


def random_world(rng, n_circles, n_segments):
    circles = [Circle((float(x), float(y)), float(r))
               for (x, y), r in zip(rng.uniform(0, SIDE, (n_circles, 2)), rng.uniform(0.3, 3.0, n_circles))]
    starts = rng.uniform(0, SIDE, (n_segments, 2))
    ends = starts + rng.normal(0.0, 4.0, (n_segments, 2))
    segments = [Segment(tuple(map(float, s)), tuple(map(float, e))) for s, e in zip(starts, ends)]
    if n_segments:
        segments.append(Segment(tuple(map(float, starts[0])), tuple(map(float, starts[0]))))   # a point wall
    return World.from_obstacles([0, 0, SIDE, SIDE], circles + segments)


def random_problem(rng, world, n_others, n_ahead):
    origin = rng.uniform(0.5, SIDE - 0.5, 2)                   # near the border too: the border term counts
    others = np.vstack([origin + rng.normal(0.0, 1.5, (n_others // 2, 2)),
                        rng.uniform(0, SIDE, (n_others - n_others // 2, 2))])
    ahead = origin + rng.normal(0.0, 2.0, (n_ahead, 2))
    return StepProblem(world, origin, rng.uniform(0, SIDE, 2), clearance=float(rng.uniform(0.3, 1.0)),
                       step_radius=float(rng.uniform(0.5, 3.0)), others=others,
                       robot_clearance=rng.uniform(0.8, 1.5, n_others), pass_on_right=ahead)


def assert_same_bits(problem, rng):
    low, high = problem.bounds().T
    for m in (0, 1, 2, 3, 8, 9, 50, 128, 301):
        X = rng.uniform(low - 0.3, high + 0.3, (m, 2))        # a few outside the box, as a test may ask
        for batch in (X, np.asfortranarray(X)):
            f, viol = problem.terms(batch)
            f_ref, viol_ref = reference_terms(problem, batch)
            assert np.array_equal(f, f_ref) and np.array_equal(viol, viol_ref)
            assert f.dtype == viol.dtype == np.float64 and f.shape == viol.shape == (m,)
            assert_same_fitness(problem, batch, f_ref, viol_ref)


def assert_same_fitness(problem, batch, f_ref, viol_ref):
    fitness = problem.fitness(batch)
    expected = np.where(viol_ref > 0.0, INFEASIBLE + viol_ref, f_ref)
    assert fitness.dtype == np.float64 and fitness.tobytes() == expected.tobytes()


@pytest.mark.parametrize('n_circles, n_segments', [(0, 0), (6, 0), (0, 5), (12, 8)])
@pytest.mark.parametrize('n_others, n_ahead', [(0, 0), (1, 1), (3, 0), (40, 2)])
def test_terms_are_the_plain_formulation_bit_for_bit(n_circles, n_segments, n_others, n_ahead):
    rng = np.random.default_rng(1000 * n_circles + 100 * n_segments + 10 * n_others + n_ahead)
    world = random_world(rng, n_circles, n_segments)
    for _ in range(15):
        assert_same_bits(random_problem(rng, world, n_others, n_ahead), rng)


def test_terms_in_a_crowd_with_many_robots_at_hand():
    """Several robots within reach of the runs and of the candidates: their columns are summed in place."""
    rng = np.random.default_rng(7)
    world = random_world(rng, 25, 4)
    origin = np.array([15.0, 15.0])
    for _ in range(10):
        others = np.vstack([origin + rng.uniform(-2.5, 2.5, (6, 2)), rng.uniform(0, SIDE, (60, 2))])
        problem = StepProblem(world, origin, np.array([29.0, 29.0]), 0.7, 2.0, others=others,
                              robot_clearance=np.full(len(others), 1.2))
        assert_same_bits(problem, rng)


def test_a_robot_that_gets_pass_on_right_later_is_scored_with_it():
    # plan_step_passing_right sets pass_on_right on a built problem (offsets from the robot) and resets it.
    rng = np.random.default_rng(3)
    problem = random_problem(rng, random_world(rng, 4, 2), 2, 0)
    problem.pass_on_right = np.array([[1.5, 0.2]])
    assert_same_bits(problem, rng)
    problem.pass_on_right = np.zeros((0, 2))
    assert_same_bits(problem, rng)


def test_fitness_of_a_lone_feasible_candidate_among_many():
    # numpy sums one column of obstacle distances pairwise and several one row after another: a lone feasible
    # candidate must get the sum it gets among the others (terms), not the one it would get alone.
    rng = np.random.default_rng(11)
    world = random_world(rng, 30, 6)
    for _ in range(20):
        # f = 1 / f1 alone (c = 0): a last bit of the sum shows in f (with c * d it is mostly rounded away).
        problem = dataclasses.replace(random_problem(rng, world, 0, 0), a=1.0, c=0.0)
        low, high = problem.bounds().T
        X = rng.uniform(low, high, (200, 2))
        f_ref, viol_ref = reference_terms(problem, X)
        feasible = np.flatnonzero(viol_ref == 0.0)
        for keep in feasible[:3]:
            outside = problem.origin + 10.0 * problem.step_radius        # infeasible: beyond the step radius
            for m in (1, 2, 5, 128, 300):   # fitness() evaluates the feasible ones alone from 128 on
                batch = np.vstack([X[keep], np.tile(outside, (m - 1, 1))])
                f_ref, viol_ref = reference_terms(problem, batch)
                assert viol_ref[0] == 0.0 and (viol_ref[1:] > 0.0).all()
                assert_same_fitness(problem, batch, f_ref, viol_ref)
                assert_same_fitness(problem, batch[::-1].copy(), f_ref[::-1], viol_ref[::-1])
