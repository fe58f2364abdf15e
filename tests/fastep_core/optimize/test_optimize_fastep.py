"""FAStep (fastep_core.optimize.fastep): convergence, reproducibility, bookkeeping, bounds, x0, inf values."""

import warnings

import numpy as np
import pytest

from fastep_core.errors import ParameterError
from fastep_core.optimize import OptimizeResult, fastep, firefly
from fastep_testing.fastep_loop import fastep_loop
from fastep_testing.objectives import BOX, RASTRIGIN_BOX, Recorder, rastrigin, shifted_sphere

CENTRE = np.array([0.7, -1.3])
sphere = shifted_sphere(CENTRE)


@pytest.mark.parametrize('seed', range(10))
def test_reaches_the_sphere_minimum(seed):
    r = fastep(sphere, BOX, max_iter=200, patience=50, rng=seed)
    assert np.linalg.norm(r.x - CENTRE) < 1e-3
    assert r.fun < 1e-6


def test_solves_rastrigin_for_most_seeds():
    funs = [fastep(rastrigin, RASTRIGIN_BOX, max_iter=200, patience=50, rng=seed).fun for seed in range(10)]
    assert sum(f < 1e-2 for f in funs) >= 8, funs


def test_stepping_ahead_beats_the_standard_algorithm_on_rastrigin():
    # Same swarm, same budget (20 fireflies, the default 30 iterations / patience 5), same seeds: the
    # stepping-ahead move and the preference rule are what differ.
    def solved(optimizer):
        return sum(optimizer(rastrigin, RASTRIGIN_BOX, n_fireflies=20, rng=seed).fun < 1e-2 for seed in range(30))
    assert solved(fastep) >= solved(firefly) + 6


def test_default_budget_on_the_planner_sized_problem():
    r = fastep(sphere, BOX, rng=0)
    assert r.nit <= 30 and r.fun < 1e-4


def test_same_seed_same_result_different_seed_different_history():
    a = fastep(rastrigin, RASTRIGIN_BOX, rng=7)
    b = fastep(rastrigin, RASTRIGIN_BOX, rng=np.random.default_rng(7))
    c = fastep(rastrigin, RASTRIGIN_BOX, rng=8)
    assert np.array_equal(a.x, b.x) and a.fun == b.fun and a.nfev == b.nfev
    assert np.array_equal(a.history, b.history)
    assert not (len(a.history) == len(c.history) and np.array_equal(a.history, c.history))


def test_generator_is_the_only_source_of_randomness():
    np.random.seed(0)
    a = fastep(sphere, BOX, rng=3)
    np.random.seed(1)
    b = fastep(sphere, BOX, rng=3)
    assert np.array_equal(a.history, b.history)


def test_history_nit_and_nfev_are_consistent():
    rec = Recorder(rastrigin)
    r = fastep(rec, RASTRIGIN_BOX, max_iter=25, patience=25, rng=1)
    assert isinstance(r, OptimizeResult)
    assert r.nit == len(r.history) <= 25
    assert r.history.dtype == np.float64
    assert np.all(np.diff(r.history) <= 0.0)
    assert r.history[-1] == r.fun
    assert r.nfev == len(rec.points)
    assert len(rec.batches) <= 1 + 2 * r.nit          # vectorised: at most two calls per iteration
    assert len(rec.batches[0]) == 50                   # the initial swarm, in one call
    assert rastrigin(r.x[None, :])[0] == r.fun         # fun is the value of x
    assert r.fun == rec.fun(rec.points).min()          # and the best of everything evaluated


def test_stops_after_patience_iterations_without_improvement():
    flat = fastep(lambda X: np.ones(len(X)), BOX, max_iter=30, patience=4, rng=0)
    assert flat.nit == 4
    assert fastep(sphere, BOX, max_iter=7, patience=100, rng=0).nit == 7
    none = fastep(sphere, BOX, max_iter=0, rng=0)
    assert none.nit == 0 and none.history.shape == (0,) and none.nfev == 50


def test_every_candidate_is_inside_the_bounds():
    # The minimum (5, 5) lies outside the box, so many moves would leave it without clipping.
    bounds = np.array([[-1.0, 1.0], [0.0, 2.0]])
    rec = Recorder(lambda X: np.sum((X - 5.0) ** 2, axis=1))
    r = fastep(rec, bounds, rng=2)
    P = rec.points
    assert np.all(P >= bounds[:, 0]) and np.all(P <= bounds[:, 1])
    assert np.allclose(r.x, [1.0, 2.0])


def needle(centre):
    """1 everywhere except within 1e-9 of centre: random search cannot find the 0."""
    return lambda X: np.where(np.linalg.norm(X - centre, axis=1) < 1e-9, 0.0, 1.0)


def test_x0_seeds_the_swarm():
    p = np.array([0.123456, -1.654321])
    with_x0 = fastep(needle(p), BOX, rng=0, x0=p[None, :])
    without = fastep(needle(p), BOX, rng=0)
    assert with_x0.fun == 0.0 and np.array_equal(with_x0.x, p)
    assert without.fun == 1.0
    rec = Recorder(sphere)
    x0 = np.array([[0.5, 0.5], [-0.25, 1.0], [9.0, 0.0]])   # the last row is clipped into the box
    fastep(rec, BOX, rng=0, x0=x0, max_iter=1)
    assert np.array_equal(rec.batches[0][:3], [[0.5, 0.5], [-0.25, 1.0], [2.0, 0.0]])


def test_the_brightest_firefly_never_accepts_a_worse_point():
    # One firefly is always the brightest: its candidates (attraction random walk, then stepping ahead when
    # that failed) must always be centred on the best point so far, although the preference rule lets other
    # fireflies accept a step up to 1 % worse (here up to 1 unit, far more than the random step).
    rec = Recorder(lambda X: 100.0 + np.abs(X[:, 0]))
    r = fastep(rec, [[-1.0, 1.0]], n_fireflies=1, max_iter=30, patience=30, rng=0)
    batches = iter(rec.batches)
    best = next(batches)[0]
    for t in range(r.nit):
        radius = 0.2 * 0.8 ** t * 2.0 / 2 * (1 + 1e-12)
        for _ in range(2):
            c = next(batches)[0]
            assert np.all(np.abs(c - best) <= radius)
            if rec.fun(c[None])[0] < rec.fun(best[None])[0]:
                best = c
                break
    assert next(batches, None) is None


def half_infinite(X):
    return np.where(X[:, 0] > 0.0, np.inf, np.sum((X - [-1.0, 0.5]) ** 2, axis=1))


@pytest.mark.filterwarnings('error::RuntimeWarning')
def test_infinite_and_huge_values_raise_no_warnings():
    with warnings.catch_warnings(), np.errstate(over='raise', invalid='raise', divide='raise'):
        warnings.simplefilter('error')
        r = fastep(half_infinite, BOX, max_iter=100, patience=30, rng=3)
        assert r.fun < 1e-6 and np.allclose(r.x, [-1.0, 0.5], atol=1e-3)
        nowhere = fastep(lambda X: np.full(len(X), np.inf), BOX, rng=0)
        assert nowhere.fun == np.inf and nowhere.nit == 5
        huge = fastep(lambda X: np.where(X[:, 1] > 0, 1.7e308, -1.7e308 * (1 - 0.1 * X[:, 0] ** 2)), BOX, rng=0)
        assert huge.fun == pytest.approx(-1.7e308, rel=1e-9) and np.isfinite(huge.history).all()
        infeasible = fastep(lambda X: 1e6 + np.abs(X[:, 0]) + np.where(X[:, 1] > 1.5, -1e6, 0.0), BOX, rng=0)
        assert infeasible.fun < 1.0


def test_nan_counts_as_infinity():
    r = fastep(lambda X: np.where(X[:, 0] > 0.0, np.nan, sphere(X)), BOX, rng=0)
    assert r.x[0] <= 0.0 and np.isfinite(r.fun)


def test_invalid_input_is_reported():
    with pytest.raises(ParameterError):
        fastep(sphere, [[1.0, -1.0], [0.0, 1.0]])
    with pytest.raises(ParameterError):
        fastep(sphere, [-1.0, 1.0])
    with pytest.raises(ParameterError):
        fastep(sphere, BOX, n_fireflies=0)
    with pytest.raises(ParameterError):
        fastep(sphere, BOX, x0=np.zeros((51, 2)))
    with pytest.raises(ParameterError):
        fastep(lambda X: np.zeros((len(X), 1)), BOX)
    with pytest.raises(ParameterError):
        fastep(sphere, BOX, rng='seed')


def test_loop_reference_reaches_the_sphere_minimum():
    r = fastep_loop(sphere, BOX, max_iter=60, patience=20, rng=0)
    assert np.linalg.norm(r.x - CENTRE) < 1e-3 and r.fun < 1e-6


@pytest.mark.parametrize('fun', [sphere, half_infinite], ids=['sphere', 'half-infinite'])
def test_loop_reference_makes_exactly_the_same_moves(fun):
    a = fastep(fun, BOX, max_iter=12, patience=12, rng=5)
    b = fastep_loop(fun, BOX, max_iter=12, patience=12, rng=5)
    assert np.array_equal(a.x, b.x) and a.fun == b.fun
    assert np.array_equal(a.history, b.history) and (a.nit, a.nfev) == (b.nit, b.nfev)


# Attraction to a sample of k brighter fireflies (attraction_sample; a departure from the paper, off by default).

@pytest.mark.parametrize('seed', range(5))
def test_attraction_sample_reaches_the_sphere_minimum(seed):
    r = fastep(sphere, BOX, max_iter=200, patience=50, rng=seed, attraction_sample=5)
    assert np.linalg.norm(r.x - CENTRE) < 1e-3 and r.fun < 1e-6


def test_attraction_sample_is_deterministic_per_seed_and_stays_in_the_box():
    bounds = np.array([[-1.0, 1.0], [0.0, 2.0]])
    a, b = Recorder(lambda X: np.sum((X - 5.0) ** 2, axis=1)), Recorder(lambda X: np.sum((X - 5.0) ** 2, axis=1))
    ra = fastep(a, bounds, rng=4, attraction_sample=3)
    rb = fastep(b, bounds, rng=np.random.default_rng(4), attraction_sample=3)
    assert np.array_equal(ra.x, rb.x) and np.array_equal(ra.history, rb.history) and ra.nfev == rb.nfev
    assert np.array_equal(a.points, b.points)
    assert np.all(a.points >= bounds[:, 0]) and np.all(a.points <= bounds[:, 1])
    rc = fastep(rastrigin, RASTRIGIN_BOX, rng=5, attraction_sample=3)
    rd = fastep(rastrigin, RASTRIGIN_BOX, rng=6, attraction_sample=3)
    assert not np.array_equal(rc.history, rd.history)


def test_attraction_sample_makes_at_most_k_candidates_per_firefly():
    rec = Recorder(rastrigin)
    r = fastep(rec, RASTRIGIN_BOX, n_fireflies=50, max_iter=4, patience=4, rng=0, attraction_sample=5)
    attraction_batches = rec.batches[1::2]                 # initial swarm, then attraction / stepping ahead
    assert r.nit == 4 and len(attraction_batches) == 4
    # Ranked fireflies 0..4 have 0..4 brighter ones (all taken; the brightest walks), the 45 others take 5.
    assert all(len(b) == 1 + (1 + 2 + 3 + 4) + 45 * 5 for b in attraction_batches)
    paper = Recorder(rastrigin)
    fastep(paper, RASTRIGIN_BOX, n_fireflies=50, max_iter=1, patience=1, rng=0)
    assert len(paper.batches[1]) == 1 + 50 * 49 // 2


def test_sampled_keeps_k_brighter_fireflies_per_row_without_replacement():
    from fastep_core.optimize.firefly import Swarm
    swarm = Swarm(8, np.zeros(2), np.ones(2), gamma=1.0, beta0=2.0)
    F = np.array([0.0, 1.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0])   # a tie: fireflies 1 and 2 outshine neither
    brighter = F < F[:, None]
    keep = swarm.sampled(brighter, np.random.default_rng(0), 3)
    assert not (keep & ~brighter).any()                              # only brighter fireflies
    assert np.array_equal(keep.sum(axis=1), np.minimum(brighter.sum(axis=1), 3))
    assert np.array_equal(keep[:4], brighter[:4])                    # three or fewer brighter: all of them
    draws = [swarm.sampled(brighter, np.random.default_rng(s), 3)[7] for s in range(40)]
    assert len({tuple(np.flatnonzero(d)) for d in draws}) > 5          # a different sample per draw


def test_attraction_sample_off_is_the_paper():
    a = fastep(rastrigin, RASTRIGIN_BOX, rng=7)
    b = fastep(rastrigin, RASTRIGIN_BOX, rng=7, attraction_sample=None)
    loop = fastep_loop(rastrigin, RASTRIGIN_BOX, rng=7)
    assert np.array_equal(a.x, b.x) and np.array_equal(a.history, b.history) and a.nfev == b.nfev
    assert np.array_equal(a.x, loop.x) and np.array_equal(a.history, loop.history)


@pytest.mark.parametrize('k', [0, -1, 2.5, True])
def test_attraction_sample_must_be_a_positive_integer(k):
    with pytest.raises(ParameterError, match='attraction_sample'):
        fastep(sphere, BOX, attraction_sample=k)


# Merged moves (merged_moves; a departure from the paper, off by default): one objective call per iteration.

@pytest.mark.parametrize('seed', range(5))
def test_merged_moves_reach_the_sphere_minimum(seed):
    r = fastep(sphere, BOX, max_iter=200, patience=50, rng=seed, merged_moves=True)
    assert np.linalg.norm(r.x - CENTRE) < 1e-3 and r.fun < 1e-6


def test_merged_moves_solve_rastrigin_as_often_as_the_paper():
    def solved(**kw):
        return sum(fastep(rastrigin, RASTRIGIN_BOX, n_fireflies=20, rng=seed, **kw).fun < 1e-2 for seed in range(30))
    assert solved(merged_moves=True) >= solved() - 3


def test_merged_moves_make_one_call_per_iteration_of_pairs_and_steps():
    rec = Recorder(rastrigin)
    r = fastep(rec, RASTRIGIN_BOX, n_fireflies=50, max_iter=4, patience=4, rng=0, merged_moves=True)
    assert r.nit == 4 and len(rec.batches) == 1 + 4
    assert all(len(b) == 1 + 50 * 49 // 2 + 50 for b in rec.batches[1:])   # every pair, then every firefly's step
    assert np.all(np.diff(r.history) <= 0.0) and r.nfev == len(rec.points)
    assert r.fun == rec.fun(rec.points).min()


@pytest.mark.parametrize('fun', [sphere, half_infinite, rastrigin], ids=['sphere', 'half-infinite', 'rastrigin'])
def test_merged_moves_are_the_loop_references_move_for_move(fun):
    a = fastep(fun, BOX, max_iter=12, patience=12, rng=5, merged_moves=True)
    b = fastep_loop(fun, BOX, max_iter=12, patience=12, rng=5, merged_moves=True)
    assert np.array_equal(a.x, b.x) and a.fun == b.fun
    assert np.array_equal(a.history, b.history) and (a.nit, a.nfev) == (b.nit, b.nfev)
    paper = fastep(fun, BOX, max_iter=12, patience=12, rng=5)
    assert not np.array_equal(a.history, paper.history)    # another run: the draws and moves differ


def test_merged_moves_with_ties_and_an_attraction_sample_follow_the_loop_reference():
    # Values in steps of 1: many fireflies tie, so the pairs are not the precomputed triangle.
    def steps(X):
        return np.floor(np.sum((X - 1.0) ** 2, axis=1))
    a = fastep(steps, BOX, max_iter=8, patience=8, rng=2, merged_moves=True)
    b = fastep_loop(steps, BOX, max_iter=8, patience=8, rng=2, merged_moves=True)
    assert np.array_equal(a.history, b.history) and np.array_equal(a.x, b.x)
    s = fastep(rastrigin, RASTRIGIN_BOX, rng=3, merged_moves=True, attraction_sample=4)
    t = fastep(rastrigin, RASTRIGIN_BOX, rng=3, merged_moves=True, attraction_sample=4)
    assert np.array_equal(s.history, t.history) and np.all(np.diff(s.history) <= 0.0)


# One iteration at a time (fastep_iterations): what a planner with a budget per control tick runs.
@pytest.mark.parametrize('seed,merged', [(0, False), (1, False), (2, False), (0, True), (1, True)])
def test_the_run_spread_over_pauses_is_fasteps_draw_for_draw(seed, merged):
    from fastep_core.optimize import fastep_iterations
    kw = dict(n_fireflies=20, max_iter=40, patience=5, tol=1e-9, merged_moves=merged)
    whole = fastep(rastrigin, RASTRIGIN_BOX, rng=np.random.default_rng(seed), **kw)
    run = fastep_iterations(rastrigin, RASTRIGIN_BOX, rng=np.random.default_rng(seed), **kw)
    pauses = 0
    with pytest.raises(StopIteration) as finished:
        while True:
            next(run)
            pauses += 1
    spread = finished.value.value
    assert pauses == whole.nit   # after the initial swarm, then after each iteration but the last
    assert np.array_equal(spread.x, whole.x) and spread.fun == whole.fun
    assert (spread.nit, spread.nfev) == (whole.nit, whole.nfev) and np.array_equal(spread.history, whole.history)


def test_bad_arguments_are_refused_at_the_first_pause():
    from fastep_core.optimize import fastep_iterations
    run = fastep_iterations(rastrigin, RASTRIGIN_BOX, n_fireflies=0)
    with pytest.raises(ParameterError):
        next(run)
