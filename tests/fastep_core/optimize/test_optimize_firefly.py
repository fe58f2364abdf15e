"""The standard firefly algorithm (fastep_core.optimize.firefly), the baseline FAStep is compared with."""

import warnings

import numpy as np
import pytest

from fastep_core.errors import ParameterError
from fastep_core.optimize import firefly
from fastep_testing.objectives import BOX, RASTRIGIN_BOX, Recorder, rastrigin, shifted_sphere

CENTRE = np.array([-0.4, 1.1])
sphere = shifted_sphere(CENTRE)


@pytest.mark.parametrize('seed', range(10))
def test_reaches_the_sphere_minimum(seed):
    r = firefly(sphere, BOX, max_iter=200, patience=50, rng=seed)
    assert np.linalg.norm(r.x - CENTRE) < 1e-3
    assert r.fun < 1e-6


def test_solves_rastrigin_for_most_seeds():
    funs = [firefly(rastrigin, RASTRIGIN_BOX, max_iter=200, patience=50, rng=seed).fun for seed in range(10)]
    assert sum(f < 1e-2 for f in funs) >= 8, funs


def test_same_seed_same_result_different_seed_different_history():
    a = firefly(rastrigin, RASTRIGIN_BOX, rng=11)
    b = firefly(rastrigin, RASTRIGIN_BOX, rng=np.random.default_rng(11))
    c = firefly(rastrigin, RASTRIGIN_BOX, rng=12)
    assert np.array_equal(a.x, b.x) and a.fun == b.fun and np.array_equal(a.history, b.history)
    assert not (len(a.history) == len(c.history) and np.array_equal(a.history, c.history))


def test_one_call_per_iteration_and_exact_bookkeeping():
    rec = Recorder(rastrigin)
    n = 30
    r = firefly(rec, RASTRIGIN_BOX, n_fireflies=n, max_iter=20, patience=20, rng=4)
    assert r.nit == len(r.history) == len(rec.batches) - 1 <= 20
    assert np.all(np.diff(r.history) <= 0.0) and r.history[-1] == r.fun
    assert r.nfev == len(rec.points)
    # With distinct values every firefly but the brightest has a candidate per brighter firefly, the
    # brightest one random walk: 1 + n (n - 1) / 2 candidates per iteration.
    assert all(len(batch) == 1 + n * (n - 1) // 2 for batch in rec.batches[1:])
    assert r.fun == rec.fun(rec.points).min()


def test_every_candidate_is_inside_the_bounds():
    bounds = np.array([[0.5, 1.5], [-3.0, -1.0]])
    rec = Recorder(lambda X: np.sum(X ** 2, axis=1))
    r = firefly(rec, bounds, rng=0)
    P = rec.points
    assert np.all(P >= bounds[:, 0]) and np.all(P <= bounds[:, 1])
    assert np.allclose(r.x, [0.5, -1.0])


def test_x0_seeds_the_swarm():
    p = np.array([1.5, -0.75])
    needle = lambda X: np.where(np.linalg.norm(X - p, axis=1) < 1e-9, 0.0, 1.0)  # noqa: E731
    assert firefly(needle, BOX, rng=0, x0=p).fun == 0.0
    assert firefly(needle, BOX, rng=0).fun == 1.0


@pytest.mark.filterwarnings('error::RuntimeWarning')
def test_infinite_values_raise_no_warnings():
    def half_infinite(X):
        return np.where(X[:, 1] < 0.0, np.inf, np.sum((X - [0.5, 1.0]) ** 2, axis=1))
    with warnings.catch_warnings(), np.errstate(over='raise', invalid='raise', divide='raise'):
        warnings.simplefilter('error')
        r = firefly(half_infinite, BOX, max_iter=100, patience=30, rng=1)
        assert r.fun < 1e-6
        assert firefly(lambda X: np.full(len(X), np.inf), BOX, rng=0).fun == np.inf


def test_invalid_input_is_reported():
    with pytest.raises(ParameterError):
        firefly(sphere, BOX, alpha=-0.1)
    with pytest.raises(ParameterError):
        firefly(sphere, BOX, patience=0)
    with pytest.raises(ParameterError):
        firefly(sphere, [[0.0, np.inf], [0.0, 1.0]])
