"""The Stepping Ahead Firefly algorithm (FAStep, Nand et al. 2021), vectorised.

Why FAStep: the FAStep-Kinematic planner calls this once per planned waypoint, so it must be fast (a few milliseconds
for the paper's 50 fireflies) and reproducible (one seeded Generator, same seed -> same bits). Where the standard
firefly algorithm stalls, FAStep tries a second move, stepping ahead of the brightest firefly, under a preference rule
that tolerates a slightly worse position (within PREFERENCE_TOLERANCE, 1 %), which helps the swarm leave local minima
(paper section IV-C). One iteration: attraction (eq. 3) as in `firefly.Swarm.attraction`, a firefly moving only to a
strictly better candidate; stepping ahead (eq. 4) for the others; the preference rule; elitism (the brightest never
gets worse) and damping of alpha. Stops after `max_iter` iterations or `patience` without improvement. Where the
authors' MATLAB code differs we follow the paper's text; defaults are its Table 1. `fastep_testing/fastep_loop.py`
makes the same moves and random draws with plain loops, bit for bit. Two departures, off by default, make a planned
step cheaper: `attraction_sample=k` and `merged_moves=True`. Objective values are only compared, so +inf and huge
values raise no warnings (NaN counts as +inf); the objective receives (m, d) arrays in Fortran order. In full (each
step, the order of random draws, the departures): docs/architecture.md, "The FAStep optimizer, step by step".
"""

from __future__ import annotations

from typing import Generator

import numpy as np
from numpy.typing import ArrayLike

from fastep_core.optimize.firefly import Elite, Swarm, _check_swarm_parameters
from fastep_core.optimize.result import (
    FloatArray,
    Objective,
    OptimizeResult,
    RngLike,
    VectorisedFunction,
    check_count,
    check_number,
    check_problem,
    initial_population,
)

__all__ = ['fastep', 'fastep_iterations', 'PREFERENCE_TOLERANCE']

PREFERENCE_TOLERANCE = 0.01
"""Q of the preference rule: a stepping-ahead move up to Q * |f_i| worse than f_i is still taken."""


def fastep(fun: VectorisedFunction, bounds: ArrayLike, *, n_fireflies: int = 50, max_iter: int = 30,
           patience: int = 5, gamma: float = 1.0, beta0: float = 2.0, alpha: float = 0.2,
           alpha_damping: float = 0.8, tol: float = 0.0, rng: RngLike = None,
           x0: ArrayLike | None = None, attraction_sample: int | None = None,
           merged_moves: bool = False) -> OptimizeResult:
    """Minimise a vectorised function over a box with the Stepping Ahead Firefly algorithm.

    Parameters
    ----------
    fun : callable
        Maps an (m, d) float array of candidates to an (m,) array of objective values (minimised). Called
        once for the initial population and at most twice per iteration. The array is in Fortran order
        (fast for row-wise numpy code); it must not be modified or relied upon after the call.
    bounds : array_like, shape (d, 2)
        [low, high] per dimension. Every evaluated candidate lies inside.
    n_fireflies, gamma, beta0, alpha, alpha_damping
        Swarm size, light absorption, attraction at distance zero, random-move scale (as a fraction of the
        box) and its damping per iteration. Defaults: Table 1 of the paper, gamma = 1 from the authors' code.
    max_iter, patience
        Stop after max_iter iterations, or after patience consecutive iterations without improvement.
    tol
        An iteration counts as an improvement only if the best value drops by more than tol (>= 0); the
        best point is still updated by smaller gains.
    rng : numpy.random.Generator, int or None
        Source of every random draw; an int or None seeds `numpy.random.default_rng`.
    x0 : array_like, shape (k, d) or (d,), optional
        Initial candidates replacing the first k fireflies (clipped into the box); k <= n_fireflies.
    attraction_sample : int >= 1, optional
        Attract each firefly to at most this many brighter fireflies, sampled at random every iteration (a
        departure from the paper, see the module docstring); None (default): to all of them, as the paper.
    merged_moves : bool
        Evaluate each iteration's attraction and stepping-ahead candidates in one call, stepping ahead of the
        brightest firefly at the iteration's start (a departure from the paper, see the module docstring);
        False (default): two calls, stepping ahead of the brightest after the attraction moves, as the paper.

    Returns
    -------
    OptimizeResult
        Best point and value, iterations, evaluated points and the best value after each iteration.
    """
    run = fastep_iterations(fun, bounds, n_fireflies=n_fireflies, max_iter=max_iter, patience=patience, gamma=gamma,
                            beta0=beta0, alpha=alpha, alpha_damping=alpha_damping, tol=tol, rng=rng, x0=x0,
                            attraction_sample=attraction_sample, merged_moves=merged_moves)
    while True:
        try:
            next(run)
        except StopIteration as finished:
            result: OptimizeResult = finished.value
            return result


def fastep_iterations(fun: VectorisedFunction, bounds: ArrayLike, *, n_fireflies: int = 50, max_iter: int = 30,
                      patience: int = 5, gamma: float = 1.0, beta0: float = 2.0, alpha: float = 0.2,
                      alpha_damping: float = 0.8, tol: float = 0.0, rng: RngLike = None,
                      x0: ArrayLike | None = None,
                      attraction_sample: int | None = None,
                      merged_moves: bool = False) -> Generator[None, None, OptimizeResult]:
    """`fastep` one iteration at a time: a generator that pauses before each iteration and returns the result.

    The first `next()` validates the arguments and evaluates the initial swarm; each further one runs an
    iteration; StopIteration carries the OptimizeResult (`.value`). The same moves, draws and result as `fastep`
    with the same arguments, however the iterations are spread out: a planner with a time budget per control
    tick runs a few of them per tick (planning/swarm/step.py, StepRun). The objective and the Generator must not be
    used by anything else between the pauses if the run is to equal `fastep`'s.
    """
    _check_swarm_parameters(n_fireflies, max_iter, patience, gamma, beta0, alpha, alpha_damping)
    check_number('tol', tol)
    if attraction_sample is not None:
        check_count('attraction_sample', attraction_sample, 1)
    low, high, gen, x0 = check_problem(bounds, rng, x0, n_fireflies)
    objective = Objective(fun)
    swarm = Swarm(n_fireflies, low, high, gamma=gamma, beta0=beta0)

    X = initial_population(n_fireflies, low, high, gen, x0).T.copy()   # (d, n), see firefly.Swarm
    F = objective(X.T)
    elite = Elite(X, F, tol=tol, patience=patience)

    alpha_t = float(alpha)
    for _ in range(max_iter):
        yield                                            # pause: the initial swarm or an iteration is done
        scale = alpha_t * swarm.span                     # alpha_t * span, a (d, 1) column
        X, F = swarm.rank(X, F)                          # 0. brightest first
        if merged_moves:
            X, F = _merged_moves(swarm, X, F, objective, gen, scale, attraction_sample)
            alpha_t *= alpha_damping
            if elite.update(X, F):
                break
            continue

        # 1. Attraction moves (eq. 3): relocate where the best candidate is strictly better.
        C, fc = swarm.attraction(X, F, objective, gen, scale, attraction_sample)
        moved = fc < F
        X = np.where(moved, C, X)
        F = np.where(moved, fc, F)

        # 2. Stepping ahead (eq. 4) of the brightest firefly, for those that did not move.
        stuck = (~moved).nonzero()[0]
        if stuck.size:
            b = int(F.argmin())
            S = swarm.candidates(X[:, b:b + 1], X.take(stuck, axis=1), gen, scale)
            fs = objective(S.T)
            # 3. Preference rule: better, or at most Q |f| worse; the brightest takes only better points.
            f = F.take(stuck)
            take = fs <= f + PREFERENCE_TOLERANCE * np.minimum(np.abs(f), 1e300)
            if not moved[b]:
                at = int(np.searchsorted(stuck, b))
                take[at] = fs[at] < f[at]
            better = stuck[take]
            X[:, better] = S[:, take]
            F[better] = fs[take]

        # 4. Elitism and damping.
        alpha_t *= alpha_damping
        if elite.update(X, F):
            break
    return elite.result(objective.nfev)


def _merged_moves(swarm: Swarm, X: FloatArray, F: FloatArray, objective: Objective, rng: np.random.Generator,
                  scale: FloatArray, sample: int | None) -> tuple[FloatArray, FloatArray]:
    """Steps 1-3 of one iteration with `merged_moves`: the attraction pairs' candidates and every firefly's step
    ahead of x_0 (the brightest at the iteration's start; X, F ranked) in one objective call, then the same rules."""
    pairs = swarm.pairs(F, rng, sample)
    m = len(pairs.i)
    origin, towards = swarm.with_steps(pairs)
    C = swarm.candidates(X.take(origin, axis=1), X.take(towards, axis=1), rng, scale)   # the pairs, then the steps
    fc = objective(C.T)
    k = swarm.best_of_pairs(pairs, fc[:m])
    fa = fc.take(k)
    moved = fa < F                                       # 1. strictly better: relocate
    fs = fc[m:]                                          # 3. the others: the preference rule (x_0: better only)
    take = fs <= F + PREFERENCE_TOLERANCE * np.minimum(np.abs(F), 1e300)
    take[0] = fs[0] < F[0]
    take &= ~moved
    X = np.where(moved, C.take(k, axis=1), X)
    F = np.where(moved, fa, F)
    X[:, take] = C[:, m:][:, take]
    F[take] = fs[take]
    return X, F
