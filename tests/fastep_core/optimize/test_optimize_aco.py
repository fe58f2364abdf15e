"""ACO_R (fastep_core.optimize.aco_r), the optimizer of the ACO-Kinematic baseline."""

import warnings

import numpy as np
import pytest

from fastep_core.errors import ParameterError
from fastep_core.optimize import aco_r
from fastep_testing.objectives import BOX, RASTRIGIN_BOX, Recorder, rastrigin, shifted_sphere

CENTRE = np.array([1.25, 0.6])
sphere = shifted_sphere(CENTRE)


@pytest.mark.parametrize('seed', range(10))
def test_reaches_the_sphere_minimum(seed):
    r = aco_r(sphere, BOX, max_iter=200, patience=50, rng=seed)
    assert np.linalg.norm(r.x - CENTRE) < 1e-3
    assert r.fun < 1e-6


def test_solves_rastrigin_for_most_seeds():
    # ACO_R with a 10-solution archive converges fast and sometimes into a neighbouring basin.
    funs = [aco_r(rastrigin, RASTRIGIN_BOX, max_iter=200, patience=50, rng=seed).fun for seed in range(10)]
    assert sum(f < 1e-2 for f in funs) >= 7, funs


def test_same_seed_same_result_different_seed_different_history():
    a = aco_r(rastrigin, RASTRIGIN_BOX, rng=21)
    b = aco_r(rastrigin, RASTRIGIN_BOX, rng=np.random.default_rng(21))
    c = aco_r(rastrigin, RASTRIGIN_BOX, rng=22)
    assert np.array_equal(a.x, b.x) and a.fun == b.fun and np.array_equal(a.history, b.history)
    assert not (len(a.history) == len(c.history) and np.array_equal(a.history, c.history))


def test_one_call_per_iteration_and_exact_bookkeeping():
    rec = Recorder(rastrigin)
    r = aco_r(rec, RASTRIGIN_BOX, archive_size=8, n_ants=25, max_iter=40, patience=40, rng=3)
    assert r.nit == len(r.history) == len(rec.batches) - 1 <= 40
    assert [len(b) for b in rec.batches] == [8] + [25] * r.nit
    assert r.nfev == 8 + 25 * r.nit == len(rec.points)
    assert np.all(np.diff(r.history) <= 0.0) and r.history[-1] == r.fun
    assert r.fun == rec.fun(rec.points).min()


def test_stops_after_patience_iterations_without_improvement():
    assert aco_r(lambda X: np.zeros(len(X)), BOX, patience=3, rng=0).nit == 3


def test_first_ants_follow_socha_and_dorigo():
    # Recompute the first iteration by hand from the documented draw order: archive, kernel uniforms, normals.
    k, m, q, xi = 10, 40, 0.5, 0.85
    rec = Recorder(sphere)
    aco_r(rec, BOX, archive_size=k, n_ants=m, q=q, xi=xi, max_iter=1, rng=5)
    gen = np.random.default_rng(5)
    archive = gen.uniform([-2.0, -2.0], [2.0, 2.0], size=(k, 2))
    assert np.array_equal(rec.batches[0], archive)
    archive = archive[np.argsort(sphere(archive), kind='stable')]
    w = np.array([np.exp(-(rank - 1) ** 2 / (2 * q ** 2 * k ** 2)) for rank in range(1, k + 1)])
    u, z = gen.random(m), gen.standard_normal((m, 2))
    for ant in range(m):
        pick = min(int(np.searchsorted(np.cumsum(w / w.sum()), u[ant], side='right')), k - 1)
        sigma = xi * np.abs(archive - archive[pick]).sum(axis=0) / (k - 1)
        expected = np.clip(archive[pick] + sigma * z[ant], -2.0, 2.0)
        assert np.allclose(rec.batches[1][ant], expected, rtol=0.0, atol=1e-12)


def test_ants_sample_around_the_best_solutions():
    # With a small q almost every ant uses the best archive member as its kernel; after the first iteration
    # on a sphere the ants concentrate around the minimum, well inside the spread of the uniform start.
    rec = Recorder(sphere)
    aco_r(rec, BOX, q=1e-3, max_iter=8, patience=8, rng=0)
    first, last = rec.batches[1], rec.batches[-1]
    spread = [np.median(np.linalg.norm(batch - CENTRE, axis=1)) for batch in (first, last)]
    assert spread[1] < 0.1 * spread[0]


def test_every_candidate_is_inside_the_bounds():
    bounds = np.array([[-1.0, 0.0], [2.0, 3.0]])
    rec = Recorder(lambda X: np.sum((X - [4.0, 0.0]) ** 2, axis=1))
    r = aco_r(rec, bounds, rng=0, max_iter=60, patience=20)
    P = rec.points
    assert np.all(P >= bounds[:, 0]) and np.all(P <= bounds[:, 1])
    assert np.allclose(r.x, [0.0, 2.0])


def test_x0_seeds_the_archive():
    p = np.array([-1.875, 0.3125])
    needle = lambda X: np.where(np.linalg.norm(X - p, axis=1) < 1e-9, 0.0, 1.0)  # noqa: E731
    assert aco_r(needle, BOX, rng=0, x0=p).fun == 0.0
    assert aco_r(needle, BOX, rng=0).fun == 1.0
    with pytest.raises(ParameterError):
        aco_r(needle, BOX, x0=np.zeros((11, 2)))


@pytest.mark.filterwarnings('error::RuntimeWarning')
def test_infinite_values_raise_no_warnings():
    def half_infinite(X):
        return np.where(X[:, 0] + X[:, 1] > 0.0, np.inf, np.sum((X - [-0.5, -1.0]) ** 2, axis=1))
    with warnings.catch_warnings(), np.errstate(over='raise', invalid='raise', divide='raise'):
        warnings.simplefilter('error')
        r = aco_r(half_infinite, BOX, max_iter=100, patience=30, rng=1)
        assert r.fun < 1e-6
        assert aco_r(lambda X: np.full(len(X), np.inf), BOX, rng=0).fun == np.inf


def test_invalid_input_is_reported():
    with pytest.raises(ParameterError):
        aco_r(sphere, BOX, archive_size=1)
    with pytest.raises(ParameterError):
        aco_r(sphere, BOX, q=0.0)
    with pytest.raises(ParameterError):
        aco_r(sphere, BOX, n_ants=0)
